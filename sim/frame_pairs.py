"""Rendered frame pairs of scenario cases, open loop: what the estimator sees in each view.

A case runs as ``bittc eval --scenarios`` runs it, with no braking (the ego keeps its
speed) until the run ends or the ego touches an actor; every frame is captured in every
view of the camera. Pairs are (frame i - ``frame_stride``, frame i), as the geofence
controller pairs them, at ``count`` frames i spread evenly over the run. Deterministic:
the same case, camera and seed render the same pixels.
"""

from __future__ import annotations

import numpy as np

from scenarios.spec import ScenarioCase
from sim.camera import CameraConfig
from sim.episode import ScenarioSim

Pair = tuple[np.ndarray, np.ndarray]  # (image_prev, image_latest), uint8 (H, W, 3) RGB


def render_pairs(
    case: ScenarioCase, camera: CameraConfig, seed: int, count: int, frame_stride: int
) -> dict[str, list[Pair]]:
    """-> view ('wide', and 'fovea' when the camera has one) -> ``count`` pairs (fewer when the
    run is shorter than ``count`` + ``frame_stride`` frames), in time order."""
    if count < 1 or frame_stride < 1:
        raise ValueError(f"count {count} and frame_stride {frame_stride}: must be >= 1")
    sim = ScenarioSim(case, camera, seed, render=True)
    try:
        truth = sim.reset()
        frames = [sim.capture()]
        while sim.collision is None and sim.done(truth) is None:
            for _ in range(sim.n_sub):
                sim.substep(0.0)
            truth = sim.truth()
            frames.append(sim.capture())
    finally:
        sim.close()
    latest = sorted({int(i) for i in np.linspace(frame_stride, len(frames) - 1, count).round()})
    views = ("wide", "fovea") if camera.fovea_zoom is not None else ("wide",)
    return {
        v: [(frames[i - frame_stride].view(v)[0], frames[i].view(v)[0]) for i in latest if i >= frame_stride]
        for v in views
    }


def pairs_of_sizes(
    cases: list[ScenarioCase],
    sizes: list[tuple[int, int]],
    fovea_zoom: float,
    seed: int,
    count: int,
    frame_stride: int,
) -> dict[tuple[int, int], list[Pair]]:
    """(H, W) [px] of ``sizes`` -> ``count`` pairs of every case at that size, case by case.
    A size that is the fovea (zoom ``fovea_zoom``) of the default camera at another of the
    sizes gets that fovea's frames; any other size is a wide view of the default camera."""
    wide_sizes = [s for s in sizes if not any(_fovea_size(w, fovea_zoom) == s for w in sizes if w != s)]
    out: dict[tuple[int, int], list[Pair]] = {s: [] for s in sizes}
    for case in cases:
        for h, w in wide_sizes:
            camera = CameraConfig(height_px=h, width_px=w, fovea_zoom=fovea_zoom)
            for view, pairs in render_pairs(case, camera, seed, count, frame_stride).items():
                size = (h, w) if view == "wide" else _fovea_size((h, w), fovea_zoom)
                if size in out and (view == "wide" or size not in wide_sizes):
                    out[size] += pairs
    return out


def _fovea_size(wide_hw: tuple[int, int], fovea_zoom: float) -> tuple[int, int]:
    fovea = CameraConfig(height_px=wide_hw[0], width_px=wide_hw[1], fovea_zoom=fovea_zoom).fovea()
    return fovea.height_px, fovea.width_px
