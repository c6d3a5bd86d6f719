"""The worker side of `bittc generate`: per-process state and one sample rendered and written.

A worker keeps a texture bank in a private temporary folder and one World rebuilt in
place for every sample; errors go back to the driver as text (it retries them).
"""

from __future__ import annotations

import gc
import os
import shutil
import tempfile
import time
import traceback
from pathlib import Path

from bittc_core.data.format import write_sample
from sim.datagen.config import GC_THRESHOLDS, GenerationConfig, sample_seed, scene_seed

_WORKER: dict = {}


def worker_init(cfg_dict: dict) -> None:
    """Per-process state: the camera, a texture bank in a private temporary folder and
    (made at the first sample) one World rebuilt in place for every sample."""
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
    import cv2

    from sim.camera import CameraConfig
    from sim.textures import TextureBank

    cv2.setNumThreads(1)
    close_worker()
    cfg = GenerationConfig(**cfg_dict)
    bank_dir = Path(tempfile.mkdtemp(prefix="bittc_bank_"))
    _WORKER.update(
        cfg=cfg,
        bank=TextureBank(cfg.seed, bank_dir, ground=cfg.ground_texture, vehicles=cfg.vehicle_texture),
        bank_dir=bank_dir,
        camera=CameraConfig(
            height_px=cfg.height_px, width_px=cfg.width_px, fps_hz=cfg.fps_hz, supersample=cfg.supersample
        ),
    )


def drop_world() -> None:
    world = _WORKER.pop("world", None)
    if world is not None:
        world.close()


def close_worker() -> None:
    drop_world()
    if "bank_dir" in _WORKER:
        shutil.rmtree(_WORKER.pop("bank_dir"), ignore_errors=True)
    _WORKER.clear()


def make_sample(cfg_dict: dict, split_dir: str, split: str, index: int) -> tuple[int, float, str | None]:
    """Render and write one sample; returns (index, seconds, error text or None)."""
    from sim.random_scene import render_clip
    from sim.scenery import RoadConfig
    from sim.sensor import CODEC_SETS, sensor_clip
    from sim.world import World

    if _WORKER.get("cfg") != GenerationConfig(**cfg_dict):
        worker_init(cfg_dict)
    t0 = time.perf_counter()
    cfg = _WORKER["cfg"]
    try:
        if "world" not in _WORKER:
            _WORKER["world"] = World(_WORKER["camera"], RoadConfig(), seed=0, bank=_WORKER["bank"])
            gc.collect()
            gc.freeze()  # what exists now lives as long as the worker
            gc.set_threshold(*GC_THRESHOLDS)
        clip = render_clip(
            scene_seed(cfg, split, index),
            _WORKER["camera"],
            cfg.clip_length,
            _WORKER["bank"],
            _WORKER["world"],
            ahead_share=cfg.ahead_share,
            fovea_share=cfg.fovea_share,
            vru_share=cfg.vru_share,
        )
        clip = sensor_clip(clip, scene_seed(cfg, split, index), cfg.realism_share, CODEC_SETS[cfg.realism_codecs])
        write_sample(
            Path(split_dir),
            index,
            clip,
            {"split": split, "index": index, "seed": sample_seed(split, index), "dataset_seed": cfg.seed},
        )
        return index, time.perf_counter() - t0, None
    except Exception:  # reported to the driver, retried there with a fresh world
        drop_world()
        return index, time.perf_counter() - t0, traceback.format_exc(limit=4)


def make_many(cfg_dict: dict, split_dir: str, split: str, indices: list[int]) -> list[tuple[int, float, str | None]]:
    return [make_sample(cfg_dict, split_dir, split, i) for i in indices]
