"""`bittc generate`: randomised TTC training data, resumable, on local processes or Ray.

Seeds: sample ``index`` of ``split`` has the sample seed ``SPLIT_SEED_BASE[split] +
index`` (disjoint ranges per split); the scene is drawn from
``SeedSequence([dataset seed, sample seed])`` and textures from a bank seeded by the
dataset seed. A (dataset seed, split, index) triple therefore gives the same bytes
whatever the worker count or backend.
"""

from __future__ import annotations

import gc
import os
import shutil
import sys
import tempfile
import time
import traceback
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import yaml

from bittc_core.data.format import SPLITS, sample_dirname, sample_is_complete, write_sample
from bittc_core.errors import ConfigError

SPLIT_SEED_BASE = {"train": 0, "val": 1_000_000_000, "test": 2_000_000_000}
MAX_SAMPLES_PER_SPLIT = 1_000_000_000
BACKENDS = ("local", "ray")  # a process pool or Ray tasks
MAX_ATTEMPTS = 3  # tries per sample before the run fails
# a sample allocates ~10^5 short-lived Python objects (mesh lists, traffic, JSON): with
# the default thresholds the cyclic GC runs often and walks every long-lived object of a
# worker (modules, the world); freezing those and collecting less often saves ~3 ms
GC_THRESHOLDS = (20_000, 50, 100)
LOCAL_CHUNK = 4  # samples per task sent to a local worker process
RAY_CHUNK = 8  # samples per Ray task
# the run statistics' steady_samples_per_s is measured over at least this many completions
# (and at least one more chunk per worker) spanning at least this long; else it is None
STEADY_MIN_SAMPLES = 20
STEADY_MIN_S = 2.0  # [s]


@dataclass(frozen=True)
class GenerationConfig:
    """What every split of one dataset shares (stored as DIR/generation.yaml)."""

    seed: int = 0
    height_px: int = 96
    width_px: int = 288
    fps_hz: float = 10.0  # [Hz]
    clip_length: int = 2  # frames per sample
    supersample: int = 1  # render at this factor and average down
    ground_texture: str = "detailed"  # sim.textures.GROUND_STYLES; "smooth" = bittc_v1's ground
    vehicle_texture: str = "plain"  # sim.textures.VEHICLE_STYLES; "detailed" = bittc_v3's vehicles
    ahead_share: float = 0.0  # share of samples with a braking case ahead (sim.random_scene.AHEAD_*)

    def __post_init__(self) -> None:
        if self.seed < 0:
            raise ConfigError(f"seed {self.seed}: must be >= 0")
        if not 2 <= self.clip_length <= 32:
            raise ConfigError(f"clip_length {self.clip_length}: must be in [2, 32]")
        if not 1.0 <= self.fps_hz <= 100.0:
            raise ConfigError(f"fps_hz {self.fps_hz}: must be in [1, 100] Hz")
        if not 0.0 <= self.ahead_share <= 1.0:
            raise ConfigError(f"ahead_share {self.ahead_share}: must be in [0, 1]")
        if self.supersample not in (1, 2, 3, 4):
            raise ConfigError(f"supersample {self.supersample}: must be 1, 2, 3 or 4")
        from sim.textures import GROUND_STYLES, VEHICLE_STYLES

        if self.ground_texture not in GROUND_STYLES:
            raise ConfigError(f"ground_texture {self.ground_texture!r}: must be one of {', '.join(GROUND_STYLES)}")
        if self.vehicle_texture not in VEHICLE_STYLES:
            raise ConfigError(f"vehicle_texture {self.vehicle_texture!r}: must be one of {', '.join(VEHICLE_STYLES)}")


def sample_seed(split: str, index: int) -> int:
    return SPLIT_SEED_BASE[split] + index


def scene_seed(cfg: GenerationConfig, split: str, index: int) -> int:
    return int(np.random.SeedSequence([cfg.seed, sample_seed(split, index)]).generate_state(1, np.uint64)[0] % (2**63))


# --------------------------------------------------------------------------- worker side
_WORKER: dict = {}


def _worker_init(cfg_dict: dict) -> None:
    """Per-process state: the camera, a texture bank in a private temporary folder and
    (made at the first sample) one World rebuilt in place for every sample."""
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
    import cv2

    from sim.camera import CameraConfig
    from sim.textures import TextureBank

    cv2.setNumThreads(1)
    _close_worker()
    cfg = GenerationConfig(**cfg_dict)
    bank_dir = Path(tempfile.mkdtemp(prefix="bittc_bank_"))
    _WORKER.update(cfg=cfg, bank=TextureBank(cfg.seed, bank_dir, ground=cfg.ground_texture, vehicles=cfg.vehicle_texture), bank_dir=bank_dir,
                   camera=CameraConfig(height_px=cfg.height_px, width_px=cfg.width_px, fps_hz=cfg.fps_hz, supersample=cfg.supersample))  # fmt: skip


def _drop_world() -> None:
    world = _WORKER.pop("world", None)
    if world is not None:
        world.close()


def _close_worker() -> None:
    _drop_world()
    if "bank_dir" in _WORKER:
        shutil.rmtree(_WORKER.pop("bank_dir"), ignore_errors=True)
    _WORKER.clear()


def make_sample(cfg_dict: dict, split_dir: str, split: str, index: int) -> tuple[int, float, str | None]:
    """Render and write one sample; returns (index, seconds, error text or None)."""
    from sim.random_scene import render_clip
    from sim.scenery import RoadConfig
    from sim.world import World

    if _WORKER.get("cfg") != GenerationConfig(**cfg_dict):
        _worker_init(cfg_dict)
    t0 = time.perf_counter()
    cfg = _WORKER["cfg"]
    try:
        if "world" not in _WORKER:
            _WORKER["world"] = World(_WORKER["camera"], RoadConfig(), seed=0, bank=_WORKER["bank"])
            gc.collect()
            gc.freeze()  # what exists now lives as long as the worker
            gc.set_threshold(*GC_THRESHOLDS)
        clip = render_clip(scene_seed(cfg, split, index), _WORKER["camera"], cfg.clip_length, _WORKER["bank"], _WORKER["world"],
                           ahead_share=cfg.ahead_share)
        write_sample(Path(split_dir), index, clip, {"split": split, "index": index, "seed": sample_seed(split, index), "dataset_seed": cfg.seed})
        return index, time.perf_counter() - t0, None
    except Exception:  # reported to the driver, retried there with a fresh world
        _drop_world()
        return index, time.perf_counter() - t0, traceback.format_exc(limit=4)


def _make_many(cfg_dict: dict, split_dir: str, split: str, indices: list[int]) -> list[tuple[int, float, str | None]]:
    return [make_sample(cfg_dict, split_dir, split, i) for i in indices]


# --------------------------------------------------------------------------- driver side
def prepare_dir(out: Path, cfg: GenerationConfig) -> None:
    """Create/validate DIR: empty, or a dataset made with the same shared config."""
    if out.exists() and not out.is_dir():
        raise ConfigError(f"output folder {str(out)!r}: exists and is not a directory")
    gen = out / "generation.yaml"
    if out.exists() and any(out.iterdir()):
        if not gen.exists():
            raise ConfigError(f"output folder {str(out)!r}: is not empty and is not a bittc dataset (no generation.yaml)")
        try:
            old = yaml.safe_load(gen.read_text())
        except yaml.YAMLError:
            raise ConfigError(f"{gen}: malformed YAML; remove the folder or choose another output folder") from None
        if not isinstance(old, dict):
            raise ConfigError(f"{gen}: not a mapping of generation settings; remove the folder or choose another output folder")
        old.setdefault("ground_texture", "smooth")  # datasets made before the option had the smooth ground
        old.setdefault("vehicle_texture", "plain")  # and the plain vehicles
        old.setdefault("ahead_share", 0.0)  # and no braking cases ahead
        mine = asdict(cfg)
        for k in sorted(set(old) | set(mine)):
            if old.get(k) != mine.get(k):
                raise ConfigError(f"output folder {str(out)!r}: was generated with {k} = {old.get(k)!r}, this run asks for {mine.get(k)!r}")
        return
    try:
        out.mkdir(parents=True, exist_ok=True)
        tmp = gen.with_name(".generation.yaml.tmp")
        tmp.write_text(yaml.safe_dump(asdict(cfg), sort_keys=True))
        os.replace(tmp, gen)
    except OSError as e:
        raise ConfigError(f"output folder {str(out)!r}: not writable ({e.strerror})") from None


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


def generate(out: Path, cfg: GenerationConfig, split: str, n_samples: int, workers: int, backend: str,
             ray_address: str | None = None, progress: bool = True) -> dict:  # fmt: skip
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
    if workers <= 0:
        raise ConfigError(f"workers {workers}: must be > 0")
    if backend not in BACKENDS:
        raise ConfigError(f"backend {backend!r}: must be one of {', '.join(BACKENDS)}")
    if ray_address is not None and backend != "ray":
        raise ConfigError(f"ray_address {ray_address!r}: needs backend 'ray'")
    if backend == "ray":
        try:
            import ray  # noqa: F401
        except ImportError:
            raise ConfigError("backend 'ray': Ray is not installed; pip install 'bittc-sim[ray]'") from None
    prepare_dir(out, cfg)
    split_dir = out / split
    todo, damaged = pending_indices(split_dir, n_samples, cfg.clip_length)
    t0 = time.perf_counter()
    run = {"split": split, "requested": n_samples, "already_done": n_samples - len(todo), "damaged_regenerated": damaged,
           "written": 0, "failed": [], "workers": workers, "backend": backend}  # fmt: skip
    if todo:
        runner = _run_ray if backend == "ray" else _run_local
        tally = runner(cfg, split_dir, split, todo, workers, ray_address, progress)
        run["written"], run["failed"] = tally.written, sorted(tally.failed)
        chunk = RAY_CHUNK if backend == "ray" else LOCAL_CHUNK
        rate = steady_rate(tally.done_at_s, skip=chunk * workers, min_samples=max(STEADY_MIN_SAMPLES, chunk * workers))
        run["steady_samples_per_s"] = round(rate, 3) if rate is not None else None
    run["seconds"] = round(time.perf_counter() - t0, 2)
    run["samples_per_s"] = round(run["written"] / run["seconds"], 3) if run["written"] else None
    from bittc_core.data.card import rebuild_manifest_and_card

    rebuild_manifest_and_card(out, cfg, run)
    if run["failed"]:
        raise ConfigError(f"{len(run['failed'])} sample(s) of {split} failed after {MAX_ATTEMPTS} tries: indices {run['failed'][:10]}; "
                       "re-run the same command to retry them")  # fmt: skip
    return run


def _progress(total: int, enabled: bool):
    from tqdm import tqdm

    return tqdm(total=total, unit="sample", disable=not enabled, smoothing=0.1, file=sys.stderr)


@dataclass
class _Tally:
    """The driver's record of worker results: successes (with their completion times),
    retries to queue, final failures."""

    todo: list[int]
    bar: object
    split: str
    written: int = 0
    failed: list = field(default_factory=list)
    done_at_s: list = field(default_factory=list)  # perf_counter() of each success

    def __post_init__(self) -> None:
        self.attempts = {i: 0 for i in self.todo}

    def account(self, results) -> list[int]:
        """Tally results; returns the indices to try again."""
        retry = []
        for index, _sec, err in results:
            self.attempts[index] += 1
            if err is None:
                self.written += 1
                self.done_at_s.append(time.perf_counter())
                self.bar.update(1)
            elif self.attempts[index] < MAX_ATTEMPTS:
                print(f"sample {self.split}/{index} failed (try {self.attempts[index]}), retrying:\n{err}", file=sys.stderr)
                retry.append(index)
            else:
                print(f"sample {self.split}/{index} failed {MAX_ATTEMPTS} times:\n{err}", file=sys.stderr)
                self.failed.append(index)
        return retry


def steady_rate(done_at_s: list[float], skip: int, min_samples: int = STEADY_MIN_SAMPLES,
                min_s: float = STEADY_MIN_S) -> float | None:
    """Samples/s between the ``skip``-th and the last completion: the throughput once
    the workers are up (process start, imports and the first world are left out).

    None unless that window holds at least ``min_samples`` completions after the
    ``skip``-th and spans at least ``min_s`` seconds: results arrive a chunk at a time,
    so a shorter window measures the burst, not the rate."""
    if len(done_at_s) < skip + 1 + max(min_samples, 1):
        return None
    span_s = done_at_s[-1] - done_at_s[skip]
    if span_s <= 0.0 or span_s < min_s:
        return None
    return (len(done_at_s) - 1 - skip) / span_s


def _run_local(cfg, split_dir, split, todo, workers, _addr, progress):
    cfg_dict = asdict(cfg)
    queue = list(todo)
    bar = _progress(len(todo), progress)
    tally = _Tally(todo, bar, split)
    pool = None
    if workers > 1:
        import multiprocessing as mp

        pool = mp.get_context("spawn").Pool(workers, initializer=_worker_init, initargs=(cfg_dict,), maxtasksperchild=2000)
    try:
        while queue:
            args = [(cfg_dict, str(split_dir), split, i) for i in queue]
            results = pool.imap_unordered(_star, args, chunksize=LOCAL_CHUNK) if pool else map(_star, args)
            queue = tally.account(results)
    finally:
        bar.close()
        if pool is not None:
            pool.close()
            pool.join()
        _close_worker()
    return tally


def _star(args):
    return make_sample(*args)


def _run_ray(cfg, split_dir, split, todo, workers, address, progress):
    import ray

    started_here = not ray.is_initialized()
    if started_here:
        if address:
            ray.init(address=address, log_to_driver=False)
        else:
            ray.init(num_cpus=workers, include_dashboard=False, log_to_driver=False)
    remote = ray.remote(num_cpus=1, max_retries=MAX_ATTEMPTS - 1, retry_exceptions=True)(_make_many)
    cfg_dict = asdict(cfg)
    bar = _progress(len(todo), progress)
    tally = _Tally(todo, bar, split)
    try:
        queue = list(todo)
        while queue:
            refs = [remote.remote(cfg_dict, str(split_dir), split, queue[k : k + RAY_CHUNK]) for k in range(0, len(queue), RAY_CHUNK)]
            queue = []
            while refs:
                done, refs = ray.wait(refs, num_returns=1)
                try:
                    results = ray.get(done[0])
                except Exception as e:  # the task itself died MAX_ATTEMPTS times
                    print(f"a Ray task failed after its retries: {e}", file=sys.stderr)
                    continue
                queue += tally.account(results)
        # samples of tasks that died without a result: still missing on disk
        missing = [i for i in todo if not (split_dir / sample_dirname(i)).exists() and i not in tally.failed]
        tally.failed.extend(missing)
    finally:
        bar.close()
        if started_here:
            ray.shutdown()
    return tally

