"""`bittc generate`: randomised TTC training data, resumable, on local processes or Ray.

Seeds: sample ``index`` of ``split`` has the sample seed ``SPLIT_SEED_BASE[split] +
index`` (disjoint ranges per split); the scene is drawn from
``SeedSequence([dataset seed, sample seed])`` and textures from a bank seeded by the
dataset seed. A (dataset seed, split, index) triple therefore gives the same bytes
whatever the worker count or backend.
"""

from __future__ import annotations

import os
import shutil
import time
from dataclasses import asdict
from pathlib import Path

import yaml

from bittc_core.data.format import SPLITS, sample_dirname, sample_is_complete
from bittc_core.errors import ConfigError
from bittc_core.parallel import LOCK_FILE, OutputLock, bounded_workers, check_workers
from sim.datagen.config import (
    BACKENDS,
    LOCAL_CHUNK,
    MAX_ATTEMPTS,
    MAX_SAMPLES_PER_SPLIT,
    RAY_CHUNK,
    STEADY_MIN_SAMPLES,
    GenerationConfig,
)
from sim.datagen.pool import run_local, run_ray, steady_rate

__all__ = ["GenerationConfig", "generate", "pending_indices", "prepare_dir"]


def prepare_dir(out: Path, cfg: GenerationConfig) -> None:
    """Create/validate DIR: empty, or a dataset made with the same shared config."""
    if out.exists() and not out.is_dir():
        raise ConfigError(f"output folder {str(out)!r}: exists and is not a directory")
    gen = out / "generation.yaml"
    # LOCK_FILE: where the lock lay before it moved beside the folder; a dataset's old one is removed below
    if out.exists() and any(p.name != LOCK_FILE for p in out.iterdir()):
        if not gen.exists():
            raise ConfigError(
                f"output folder {str(out)!r}: is not empty and is not a bittc dataset (no generation.yaml)"
            )
        try:
            old = yaml.safe_load(gen.read_text())
        except yaml.YAMLError:
            raise ConfigError(f"{gen}: malformed YAML; remove the folder or choose another output folder") from None
        if not isinstance(old, dict):
            raise ConfigError(
                f"{gen}: not a mapping of generation settings; remove the folder or choose another output folder"
            )
        old.setdefault("ground_texture", "smooth")  # datasets made before the option had the smooth ground
        old.setdefault("vehicle_texture", "plain")  # and the plain vehicles
        old.setdefault("ahead_share", 0.0)  # and no braking cases ahead
        old.setdefault("fovea_share", 0.0)  # and no fovea scenes
        old.setdefault("realism_share", 0.0)  # and no sensor effects
        old.setdefault("realism_codecs", "jpeg")  # and JPEG the sensor's only compression
        old.setdefault("vru_share", 0.0)  # and no pedestrians or cyclists
        mine = asdict(cfg)
        a, b = _as_written(old), _as_written(mine)
        for k in sorted(set(a) | set(b)):
            if a.get(k) != b.get(k):
                raise ConfigError(
                    f"output folder {str(out)!r}: was generated with {k} = {old.get(k)!r}, "
                    f"this run asks for {mine.get(k)!r}"
                )
        (out / LOCK_FILE).unlink(missing_ok=True)
        return
    try:
        out.mkdir(parents=True, exist_ok=True)
        tmp = gen.with_name(".generation.yaml.tmp")
        tmp.write_text(yaml.safe_dump(_as_written(asdict(cfg)), sort_keys=True))
        os.replace(tmp, gen)
    except OSError as e:
        raise ConfigError(f"output folder {str(out)!r}: not writable ({e.strerror})") from None


def _as_written(settings: dict) -> dict:
    """The settings as generation.yaml holds them: a key added since is left out at its old
    meaning, so that the bytes of the datasets made before it stay as they were."""
    out = dict(settings)
    for key in ("realism_share", "vru_share"):
        if out.get(key) == 0.0:
            del out[key]
    if "realism_share" not in out or out.get("realism_codecs") == "jpeg":
        out.pop("realism_codecs", None)  # no sensor, or JPEG its only compression, as before the video codec
    return out


def pending_indices(split_dir: Path, n: int, clip_length: int) -> tuple[list[int], int]:
    """Indices still to make (missing or damaged); also removes stale temporary folders."""
    split_dir.mkdir(parents=True, exist_ok=True)
    for stale in split_dir.glob(".tmp-*"):
        shutil.rmtree(stale, ignore_errors=True)
    todo, damaged = [], 0
    for i in range(n):
        d = split_dir / sample_dirname(i)
        if not d.exists():
            todo.append(i)
        elif not sample_is_complete(d, clip_length):
            damaged += 1
            todo.append(i)
    return todo, damaged


def generate(
    out: Path,
    cfg: GenerationConfig,
    split: str,
    n_samples: int,
    workers: int,
    backend: str,
    ray_address: str | None = None,
    progress: bool = True,
) -> dict:
    """Make samples 0..n-1 of ``split`` in ``out``; returns run statistics.

    ``steady_samples_per_s`` (present when something was made): the rate after each
    worker's first chunk (``steady_rate``), or None when that window is too short to
    measure (fewer than ``STEADY_MIN_SAMPLES`` completions or one chunk per worker, or
    under ``STEADY_MIN_S``); ``samples_per_s`` counts the whole run, start-up included.
    """
    if split not in SPLITS:
        raise ConfigError(f"split {split!r}: must be one of {', '.join(SPLITS)}")
    if not 0 < n_samples <= MAX_SAMPLES_PER_SPLIT:
        raise ConfigError(f"samples {n_samples}: must be in [1, {MAX_SAMPLES_PER_SPLIT}]")
    check_workers(workers, local=backend != "ray")
    if backend not in BACKENDS:
        raise ConfigError(f"backend {backend!r}: must be one of {', '.join(BACKENDS)}")
    if ray_address is not None and backend != "ray":
        raise ConfigError(f"ray_address {ray_address!r}: needs backend 'ray'")
    if backend == "ray":
        try:
            import ray  # noqa: F401
        except ImportError:
            raise ConfigError("backend 'ray': Ray is not installed; pip install 'bittc-sim[ray]'") from None
    if out.exists() and not out.is_dir():
        raise ConfigError(f"output folder {str(out)!r}: exists and is not a directory")
    # a second generator into this folder is refused while this one runs; the lock file
    # lies beside the folder, which holds only the dataset
    with OutputLock.beside(out, "output folder"):
        prepare_dir(out, cfg)
        return _generate_locked(out, cfg, split, n_samples, workers, backend, ray_address, progress)


def _generate_locked(out, cfg, split, n_samples, workers, backend, ray_address, progress) -> dict:
    split_dir = out / split
    todo, damaged = pending_indices(split_dir, n_samples, cfg.clip_length)
    t0 = time.perf_counter()
    run = {
        "split": split,
        "requested": n_samples,
        "already_done": n_samples - len(todo),
        "damaged_regenerated": damaged,
        "written": 0,
        "failed": [],
        "workers": workers,
        "backend": backend,
    }
    if todo:
        workers = run["workers"] = bounded_workers(workers, len(todo), local=backend != "ray")
        runner = run_ray if backend == "ray" else run_local
        tally = runner(cfg, split_dir, split, todo, workers, ray_address, progress)
        run["written"], run["failed"] = tally.written, sorted(tally.failed)
        chunk = RAY_CHUNK if backend == "ray" else LOCAL_CHUNK
        rate = steady_rate(tally.done_at_s, skip=chunk * workers, min_samples=max(STEADY_MIN_SAMPLES, chunk * workers))
        run["steady_samples_per_s"] = round(rate, 3) if rate is not None else None
    run["seconds"] = round(time.perf_counter() - t0, 2)
    run["samples_per_s"] = round(run["written"] / run["seconds"], 3) if run["written"] else None
    from bittc_core.data.card import rebuild_manifest_and_card

    rebuild_manifest_and_card(out, cfg)  # the run's statistics (timings, workers) are returned, not stored
    if run["failed"]:
        raise ConfigError(
            f"{len(run['failed'])} sample(s) of {split} failed after {MAX_ATTEMPTS} tries: "
            f"indices {run['failed'][:10]}; "
            "re-run the same command to retry them"
        )
    return run
