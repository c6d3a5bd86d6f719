"""The manifest of an ONNX export folder (``manifest.json``) and its checks.

An export folder holds one ``<graph>.onnx`` per graph of ``bittc_core.export.graphs`` and
``manifest.json``::

    format          "bittc-onnx/1"
    model_config    asdict(ModelConfig) of the checkpoint; config_name its registry name
    weights         {"file": the checkpoint's name, "sha256": its hash, "release": its
                     release name (docs/releases.md) or null}
    image           {"height_px", "width_px", "layout": "NCHW", "channels": "RGB",
                     "range": [0, 1], "normalisation": "(x - 0.5) / 0.5, inside the graphs"}
    frame_dt_s      [s] the frame interval the network was trained at
    eta_range       [eta(tau_min_s), eta(tau_max_s)]: the trained geofence range, with
                     tau_range_s; continuous: cont_eta_min, cont_eta_max, cont_levels
    opset           the ONNX opset
    graphs          graph -> {"file", "sha256", "inputs": [{name, shape, dtype}],
                     "outputs": [...]}; a shape lists ints and the names of dynamic axes
                     ("views" V, "thresholds" K)
    exporter        {"torch": version, "onnx": version, "created": ISO date}

Reading it checks the format, that every graph file is there with its hash (a
truncated or edited file is refused), and, given a checkpoint, that the folder was
exported from that checkpoint (the same config and weights hash).
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

from bittc_core.errors import ConfigError

FORMAT = "bittc-onnx/1"
MANIFEST = "manifest.json"
KEYS = (
    "format",
    "config_name",
    "model_config",
    "weights",
    "image",
    "frame_dt_s",
    "tau_range_s",
    "eta_range",
    "continuous",
    "opset",
    "graphs",
    "exporter",
)


class ExportError(ConfigError):
    """An export folder that is missing, corrupt, or of another checkpoint."""


def sha256_file(path: str | Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def read_manifest(folder: str | Path, *, graphs: tuple[str, ...], verify_hashes: bool = True) -> dict:
    """Load and check ``folder/manifest.json`` and its graph files; -> the manifest."""
    folder = Path(folder)
    path = folder / MANIFEST
    if not folder.is_dir():
        raise ExportError(f"ONNX export folder {str(folder)!r}: no such folder (`bittc export` makes one)")
    if not path.is_file():
        raise ExportError(f"{str(path)!r}: no manifest; is {str(folder)!r} an ONNX export folder?")
    try:
        m = json.loads(path.read_text())
    except (ValueError, UnicodeDecodeError) as e:
        raise ExportError(f"{str(path)!r}: not valid JSON ({e})") from None
    if not isinstance(m, dict) or m.get("format") != FORMAT:
        raise ExportError(
            f"{str(path)!r}: not a {FORMAT} manifest (format {m.get('format') if isinstance(m, dict) else None!r})"
        )
    missing = [k for k in KEYS if k not in m]
    if missing:
        raise ExportError(f"{str(path)!r}: lacks the keys {missing}")
    for name in graphs:
        g = m["graphs"].get(name)
        if not isinstance(g, dict) or not {"file", "sha256", "inputs", "outputs"} <= set(g):
            raise ExportError(f"{str(path)!r}: no complete entry for the graph {name!r}")
        file = folder / g["file"]
        if not file.is_file():
            raise ExportError(f"{str(file)!r}: missing (the manifest lists it for the graph {name!r})")
        if verify_hashes and sha256_file(file) != g["sha256"]:
            raise ExportError(f"{str(file)!r}: corrupt or edited (its sha256 is not the manifest's)")
    return m


def check_matches_checkpoint(manifest: dict, folder: str | Path, ckpt: dict, weights_path: str | Path) -> None:
    """Refuse an export made from another config or other weights than ``ckpt``."""
    from dataclasses import asdict

    if manifest["config_name"] != ckpt["config_name"] or manifest["model_config"] != json.loads(
        json.dumps(asdict(ckpt["model_config"]))
    ):
        raise ExportError(
            f"ONNX export {str(folder)!r} is of config {manifest['config_name']!r}, not of the "
            f"checkpoint {str(weights_path)!r} ({ckpt['config_name']!r}); export it again"
        )
    digest = sha256_file(weights_path)
    if manifest["weights"]["sha256"] != digest:
        raise ExportError(
            f"ONNX export {str(folder)!r} was made from other weights (sha256 "
            f"{manifest['weights']['sha256'][:12]}...) than {str(weights_path)!r} ({digest[:12]}...); "
            "export it again"
        )
