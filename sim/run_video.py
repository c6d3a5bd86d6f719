"""The camera.mp4 frame of a closed-loop run: the views with fences or exact TTC over them, and the HUD."""

from __future__ import annotations

import math

import cv2
import numpy as np

from controllers.stages import MAX_DECEL_MPS2
from sim.loop import ClosedLoop
from sim.video import hud, ttc_overlay


def _view_image(frame, rec, loop: ClosedLoop, name: str, view) -> np.ndarray:
    """One view's frame with the controller's fences over it, or the exact TTC where it has none."""
    from sim.video import geofence_overlay

    img = frame.view(name)[0]
    if view is not None:
        return geofence_overlay(img, view)
    gt = loop.ground_truth(rec.index, name)
    return ttc_overlay(img, gt.tau_s, gt.valid, gt.instance) if gt is not None else img


def video_frame(frame, rec, loop: ClosedLoop, scale: int) -> np.ndarray:
    """The wide view (fences or exact TTC over it) scaled up, the fovea as an inset in its
    lower right corner with its footprint outlined on the wide view, and the HUD."""
    from sim.video import fovea_inset

    active, truth = rec.active, rec.truth
    img = _view_image(frame, rec, loop, "wide", active.view)
    img = cv2.resize(img, (img.shape[1] * scale, img.shape[0] * scale), interpolation=cv2.INTER_NEAREST)
    if frame.fovea is not None:
        inset = _view_image(frame, rec, loop, "fovea", active.fovea_view)
        img = fovea_inset(img, inset, loop.sim.camera, scale)
    crit = truth.critical
    ttc = f"{crit.ttc_s:.2f} s" if crit and math.isfinite(crit.ttc_s) else "inf"
    gap = f"{crit.gap_m:.1f} m" if crit else "-"
    stage = (
        "FULL BRAKE"
        if active.decel_mps2 >= MAX_DECEL_MPS2 - 0.1
        else "BRAKE"
        if active.decel_mps2 > 0
        else "WARNING"
        if active.warning
        else "-"
    )
    last = next((r for r in reversed(loop.records) if r.latency_s is not None), None)
    lat = f"{last.latency_s * 1e3:.0f} ms" if last is not None else "-"
    alert = active.warning or active.decel_mps2 > 0
    # the view whose fence fired in the job behind the command in effect; a latched stage holds without one
    fired = active.telemetry.get("fired_view") or ("none (stage held)" if alert else "-")
    lines = [
        f"t {rec.t_s:5.2f} s   speed {rec.ego_speed_mps * 3.6:5.1f} km/h",
        f"gap {gap}   exact TTC {ttc}",
        f"{stage}  {active.decel_mps2:.1f} m/s2   latency {lat}",
    ]
    if frame.fovea is not None:
        lines.append(f"fired in view: {fired}")
    return hud(img, lines, alert)
