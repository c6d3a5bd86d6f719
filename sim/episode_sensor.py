"""A scenario run's images through a camera sensor model (``sim.sensor``): each view moved
by the exact motion since the previous capture (for the first capture, since the state one
frame interval before it)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from sim.episode_records import Frame


def through_sensor(sim, frame: Frame, prev: Frame | None) -> Frame:
    """``frame`` with each view's image through ``sim.sensor``, blurred and shuttered by the
    exact flow from ``prev`` (or from ``frame_before(sim, frame)``)."""
    from sim.sensor import apply_effects

    if prev is None:
        prev = frame_before(sim, frame)
    out = {}
    for view in ("wide", "fovea") if frame.fovea is not None else ("wide",):
        flow = sim.ground_truth(prev, frame, view).flow_px
        dt = frame.t_s - prev.t_s
        out[view] = apply_effects(frame.view(view)[0], sim.sensor, flow, dt, sim._sensor_rng, sim._codecs[view])
    fovea = replace(frame.fovea, rgb=out["fovea"]) if frame.fovea is not None else None
    return replace(frame, image=out["wide"], fovea=fovea)


def frame_before(sim, frame: Frame) -> Frame:
    """The state one frame interval before ``frame`` (no image): the ego and every actor moved
    back at their present velocities (road users' limbs with their bodies), so the first
    capture has a motion too."""
    dt = sim.camera.dt_s
    vx, vy = sim.ego.world_velocity()
    shift = np.eye(4)
    shift[:3, 3] = (vx * dt, vy * dt, 0.0)  # world_T_cam moved back by v dt
    poses, part_T = {}, {}
    for a in sim.actors:
        x, y, h = frame.poses[a.instance]
        ax, ay = a.vehicle.world_velocity()
        poses[a.instance] = (x - ax * dt, y - ay * dt, h)
        for pid in a.part_ids:
            T = frame.part_poses[pid].copy()
            T[:2, 3] -= (ax * dt, ay * dt)
            part_T[pid] = T
    return Frame(frame.t_s - dt, None, frame.cam_T_world @ shift, poses, part_poses=part_T)
