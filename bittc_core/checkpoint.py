"""Checkpoints: save atomically, load safely, rebuild the network with no flags.

Layout (a dict, loadable with ``torch.load(..., weights_only=True)``):
    config       asdict(ModelConfig)
    config_name  the registry name it was built from ("cpu-small", ...)
    state_dict   the network weights
    train_meta   {"step": int, "stage": str, "val_miou": float, "frame_dt_s": float, ...}
    train_state  optional: optimizer / scheduler / RNG state for ``bittc train --resume``
"""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path

import torch

from bittc_core.atomic import open_temp_beside
from bittc_core.errors import ConfigError
from bittc_core.model import CONFIGS, BinaryTTCNet, ModelConfig, get_config
from bittc_core.model.config import GROWTH_COUNTS, GROWTH_FLAGS, GROWTH_SWITCHES

DEFAULT_WEIGHTS = Path(__file__).resolve().parent / "weights" / "bittc_default.pt"
TRAIN_DEFAULT_HINT = "SHIP=1 bash docs/train_fovea_weights.sh DATA_V6 OUT (docs/training.md)"
REQUIRED_KEYS = ("config", "config_name", "state_dict", "train_meta")


class CheckpointError(ConfigError):
    """A checkpoint that is missing, corrupt, or of another config."""


def save_checkpoint(path: str | os.PathLike, payload: dict) -> None:
    """Write ``payload`` to ``path`` atomically (temp file in the same folder, rename)."""
    missing = [k for k in REQUIRED_KEYS if k not in payload]
    if missing:
        raise ValueError(f"checkpoint payload lacks {missing}")
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = open_temp_beside(path)
    except OSError as e:
        raise CheckpointError(f"checkpoint {str(path)!r}: cannot write there ({e.strerror})") from None
    try:
        with os.fdopen(fd, "wb") as f:
            torch.save(payload, f)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def make_payload(net: BinaryTTCNet, config_name: str, train_meta: dict, train_state: dict | None = None) -> dict:
    payload = {
        "config": dataclasses.asdict(net.config),
        "config_name": config_name,
        "state_dict": net.state_dict(),
        "train_meta": dict(train_meta),
    }
    if train_state is not None:
        payload["train_state"] = train_state
    return payload


def release_payload(ckpt: dict) -> dict:
    """What a shipped file keeps of a loaded checkpoint: ``REQUIRED_KEYS`` only (not the
    resumable ``train_state``, nor ``model_config``, which loading derives)."""
    return {k: ckpt[k] for k in REQUIRED_KEYS}


def release_name(ckpt: dict) -> str | None:
    """The release name of a loaded checkpoint (``train_meta["release"]``, docs/releases.md),
    or None for an unnamed file."""
    return ckpt["train_meta"].get("release")


def load_checkpoint(
    path: str | os.PathLike, map_location: str | torch.device = "cpu", expected_config: str | None = None
) -> dict:
    """Load and validate. ``expected_config``: the registry name the caller needs."""
    path = Path(path)
    if not path.is_file():
        hint = f"; train it with `{TRAIN_DEFAULT_HINT}`" if path == DEFAULT_WEIGHTS else ""
        raise CheckpointError(f"no checkpoint at {str(path)!r}{hint}")
    try:
        ckpt = torch.load(path, map_location=map_location, weights_only=True)
    except Exception:  # pickle/zip errors of a truncated or foreign file
        # (torch's own message advises loading with weights_only=False: never for a checkpoint)
        raise CheckpointError(
            f"{str(path)!r} is not a bittc checkpoint (unreadable: corrupt, truncated or another kind of file)"
        ) from None
    if not isinstance(ckpt, dict) or any(k not in ckpt for k in REQUIRED_KEYS):
        raise CheckpointError(f"{str(path)!r} is not a bittc checkpoint (it lacks the keys {list(REQUIRED_KEYS)})")
    try:
        ckpt["model_config"] = ModelConfig.from_dict(ckpt["config"])
    except (TypeError, ValueError) as err:
        raise CheckpointError(f"checkpoint {str(path)!r} has an invalid config: {err}") from None
    if expected_config is not None:
        _check_config(ckpt, path, expected_config)
    return ckpt


def _check_config(ckpt: dict, path: str | os.PathLike, expected_config: str) -> None:
    """A loaded checkpoint is of registry config ``expected_config``, by name and sizes."""
    name = ckpt["config_name"]
    if name != expected_config:
        raise CheckpointError(f"checkpoint {str(path)!r} is of config {name!r}, not {expected_config!r}")
    if expected_config in CONFIGS and CONFIGS[expected_config] != ckpt["model_config"]:
        raise CheckpointError(
            f"checkpoint {str(path)!r} says config {name!r} but its sizes differ from the registered ones"
        )


def build_network(ckpt: dict) -> BinaryTTCNet:
    """A network with the checkpoint's config and weights (on the state_dict's device)."""
    net = BinaryTTCNet(ckpt["model_config"])
    try:
        net.load_state_dict(ckpt["state_dict"])
    except RuntimeError as err:
        raise CheckpointError(
            f"checkpoint weights do not fit config {ckpt['config_name']!r}: {str(err).splitlines()[0]}"
        ) from None
    return net


def init_network(path: str | os.PathLike, config_name: str) -> BinaryTTCNet:
    """A network of config ``config_name`` starting from the weights of ``path``.

    The checkpoint's config must be that config, or one it grows from: the same sizes
    with fewer growth blocks, without the global-context block, the correlation volume or
    its shifted or column correlations (``GROWTH_COUNTS``, ``GROWTH_FLAGS``, ``GROWTH_SWITCHES`` in
    ``bittc_core.model.config``). The added modules keep their
    initialisation, the identity, so the network computes what the checkpoint did.
    """
    ckpt = load_checkpoint(path, map_location="cpu")
    name, source, target = ckpt["config_name"], ckpt["model_config"], get_config(config_name)
    if name == config_name:
        _check_config(ckpt, path, config_name)
        return build_network(ckpt)
    if CONFIGS.get(name) != source or not grows_into(source, target):
        raise CheckpointError(
            f"initial checkpoint {str(path)!r}: its config ({name!r}) is neither "
            f"{config_name!r} nor a config {config_name!r} grows from "
            "(the same sizes with fewer growth blocks, no global-context block, no "
            "correlation volume, or no shifted or column correlations)"
        )
    net = BinaryTTCNet(target)
    added = set(net.state_dict()) - set(BinaryTTCNet(source).state_dict())
    missing, unexpected = net.load_state_dict(ckpt["state_dict"], strict=False)
    # (batch norm fills in a missing num_batches_tracked itself, so it is never missing)
    if not set(missing) <= added or unexpected:
        raise CheckpointError(
            f"initial checkpoint {str(path)!r}: weights do not fit config {config_name!r} "
            f"(missing {sorted(set(missing) - added)}, unexpected {unexpected})"
        )
    return net


def grows_into(source: ModelConfig, target: ModelConfig) -> bool:
    """True when ``target`` is ``source`` plus identity-at-init modules only."""
    if source == target:
        return False
    fields = (*GROWTH_COUNTS, *GROWTH_FLAGS, *GROWTH_SWITCHES)
    if source.corr_groups == 0:
        fields += ("corr_log_step",)  # unused without the volume
    if dataclasses.replace(source, **{n: getattr(target, n) for n in fields}) != target:
        return False  # some other field differs
    switched = all(getattr(source, n) in (0, getattr(target, n)) for n in GROWTH_SWITCHES)
    return switched and all(getattr(source, n) <= getattr(target, n) for n in (*GROWTH_COUNTS, *GROWTH_FLAGS))


def pick_device(name: str = "auto") -> torch.device:
    """ "auto" -> cuda when available, else cpu; "cpu"/"cuda" as asked."""
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    if name == "cuda" and not torch.cuda.is_available():
        raise ConfigError("device 'cuda': no CUDA device is available")
    if name not in ("cpu", "cuda"):
        raise ConfigError(f"device {name!r}: expected auto, cpu or cuda")
    return torch.device(name)
