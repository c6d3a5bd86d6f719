"""Exact per-actor truth from future paths: will this actor touch the ego if nobody brakes?

For crossing road users, junction traffic and a turning ego, "in path" is not a lateral
overlap now but a contact later. Both futures are known exactly: the ego keeps its
present speed along its nominal path (``scenarios.paths.EgoPath``), each actor follows
its script (a walker's ``pose_at``; a scripted car drives straight at its present
velocity, as its script says). The footprints are swept over ``HORIZON_S`` in steps of
``STEP_S``; the first overlap is the time to collision.

Convention (as :class:`sim.actor_truth.ActorTruth`): ``ttc_s`` is bumper to bumper (the
footprints touch); ``closing_speed_mps`` is the ego's speed minus the actor's velocity
along the ego's heading, ``gap_m`` = closing speed x TTC (the distance the ego must shed
to stay clear; for a crossing target, the distance to the point where the paths meet).
An actor is ``in_path`` when a contact is predicted within the horizon. ``must_brake``:
even if the ego began full braking ``BRAKE_LEAD_S`` from now (then the actuator's delay
and jerk-limited build-up, approximated by half the build-up at constant speed) the
footprints would still touch; the last moment that braking avoids a target that crosses
the ego's path (a stopped ego can stand in a crossing car's way).
"""

from __future__ import annotations

import math

import numpy as np

from sim.actor_truth import ActorTruth

HORIZON_S = 6.0  # [s] how far ahead contacts are predicted
STEP_S = 0.02  # [s]
BRAKE_LEAD_S = 0.3  # [s] the margin before full braking in the must-brake test (the oracle's next frames)
BRAKE_DELAY_S = 0.1 + 0.15  # [s] the actuator's delay plus half its build-up to full braking (sim.traffic)
FULL_DECEL_MPS2 = 9.0  # [m/s^2]


def rectangles(x, y, heading, length_m: float, width_m: float) -> np.ndarray:
    """(N, 4, 2) corners of N oriented rectangles."""
    c, s = np.cos(heading), np.sin(heading)
    local = np.array([[1, 1], [1, -1], [-1, -1], [-1, 1]]) * [length_m / 2, width_m / 2]
    R = np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)  # (N, 2, 2)
    return np.einsum("nij,kj->nki", R, local) + np.stack([x, y], -1)[:, None, :]


def overlapping(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(N,) bool: rectangle a[n] overlaps b[n] (separating-axis test on both edge sets)."""
    out = np.ones(len(a), dtype=bool)
    for poly in (a, b):
        edges = np.roll(poly, -1, axis=1) - poly  # (N, 4, 2)
        axes = np.stack([-edges[..., 1], edges[..., 0]], -1)  # (N, 4, 2)
        pa = np.einsum("nkd,njd->nkj", axes, a)
        pb = np.einsum("nkd,njd->nkj", axes, b)
        sep = (pa.max(-1) < pb.min(-1)) | (pb.max(-1) < pa.min(-1))
        out &= ~sep.any(-1)
    return out


def ego_future(path, ego_pose, speed_mps: float, times: np.ndarray, brake_from_s: float | None = None):
    """(x, y, heading) arrays of the ego along ``path`` after ``times`` [s]: at constant speed,
    or braking at ``FULL_DECEL_MPS2`` from ``brake_from_s`` [s] on until it stops."""
    s0 = path.closest_s(ego_pose[0], ego_pose[1])
    if brake_from_s is None:
        dist = speed_mps * times
    else:
        tb = np.clip(times - brake_from_s, 0.0, speed_mps / FULL_DECEL_MPS2)
        dist = speed_mps * np.minimum(times, brake_from_s) + speed_mps * tb - 0.5 * FULL_DECEL_MPS2 * tb**2
    poses = np.array([path.pose_at(s0 + d) for d in dist])
    return poses[:, 0], poses[:, 1], poses[:, 2]


def actor_future(vehicle, t_now_s: float, times: np.ndarray) -> tuple[np.ndarray, ...]:
    """(x, y, heading) of an actor after ``times`` [s]: a walker's scripted poses, else
    straight on at its present velocity."""
    if hasattr(vehicle, "pose_at") and not getattr(vehicle, "halted", False):
        poses = np.array([vehicle.pose_at(t_now_s + t) for t in times])
        return poses[:, 0], poses[:, 1], poses[:, 2]
    x, y, h = vehicle.world_pose()
    vx, vy = vehicle.world_velocity()
    return x + vx * times, y + vy * times, np.full_like(times, h)


def path_truth(
    instance: int,
    path,
    ego_pose,
    ego_size_m,
    ego_speed_mps: float,
    vehicle,
    actor_size_m,
    t_now_s: float,
) -> ActorTruth:
    """Truth of one actor from both exact futures (see the module docstring)."""
    times = np.arange(0.0, HORIZON_S + 1e-9, STEP_S)
    ex, ey, eh = ego_future(path, ego_pose, ego_speed_mps, times)
    ax, ay, ah = actor_future(vehicle, t_now_s, times)
    actor = rectangles(ax, ay, ah, *actor_size_m)
    hit = overlapping(rectangles(ex, ey, eh, *ego_size_m), actor)
    ttc = float(times[np.argmax(hit)]) if hit.any() else math.inf
    must = False
    if math.isfinite(ttc) and ego_speed_mps > 0:
        bx, by, bh = ego_future(path, ego_pose, ego_speed_mps, times, BRAKE_LEAD_S + BRAKE_DELAY_S)
        must = bool(overlapping(rectangles(bx, by, bh, *ego_size_m), actor).any())
    heading = ego_pose[2]
    along = np.array([math.cos(heading), math.sin(heading)])
    rel = np.array(vehicle.world_pose()[:2]) - np.array(ego_pose[:2])
    lateral = float(rel @ np.array([-along[1], along[0]]))
    closing = ego_speed_mps - float(np.asarray(vehicle.world_velocity()) @ along)
    in_path = math.isfinite(ttc)
    ahead = in_path or float(rel @ along) > 0
    gap = closing * ttc if in_path else float(rel @ along) - ego_size_m[0] / 2
    return ActorTruth(instance, float(gap), lateral, float(closing), ttc, in_path, bool(ahead), must)
