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
from sim.vehicles import footprint_corners_many, footprints_overlap_many

HORIZON_S = 6.0  # [s] how far ahead contacts are predicted
STEP_S = 0.02  # [s]
BRAKE_LEAD_S = 0.3  # [s] the margin before full braking in the must-brake test (the oracle's next frames)
BRAKE_DELAY_S = 0.1 + 0.15  # [s] the actuator's delay plus half its build-up to full braking (sim.traffic)
FULL_DECEL_MPS2 = 9.0  # [m/s^2]


class EgoFuture:
    """The ego's footprints over the horizon from its state now, shared by every actor's
    truth: at constant speed along its path, and (``braked``, computed when first asked)
    braking fully from ``BRAKE_LEAD_S`` + ``BRAKE_DELAY_S`` on."""

    def __init__(self, path, ego_pose, ego_size_m, speed_mps: float) -> None:
        self.times = np.arange(0.0, HORIZON_S + 1e-9, STEP_S)
        self.pose, self.size_m, self.speed_mps = ego_pose, ego_size_m, speed_mps
        self._path, self._s0 = path, path.closest_s(ego_pose[0], ego_pose[1])
        self.rects = self._footprints(speed_mps * self.times)
        self._braked: np.ndarray | None = None

    @property
    def braked(self) -> np.ndarray:
        if self._braked is None:
            v, t_b = self.speed_mps, BRAKE_LEAD_S + BRAKE_DELAY_S
            tb = np.clip(self.times - t_b, 0.0, v / FULL_DECEL_MPS2)
            self._braked = self._footprints(v * np.minimum(self.times, t_b) + v * tb - 0.5 * FULL_DECEL_MPS2 * tb**2)
        return self._braked

    def _footprints(self, dist_m: np.ndarray) -> np.ndarray:
        poses = np.array([self._path.pose_at(self._s0 + d) for d in dist_m])
        return footprint_corners_many(poses[:, 0], poses[:, 1], poses[:, 2], *self.size_m)


def actor_future(vehicle, t_now_s: float, times: np.ndarray) -> tuple[np.ndarray, ...]:
    """(x, y, heading) of an actor after ``times`` [s]: a walker's scripted poses, else
    straight on at its present velocity."""
    if hasattr(vehicle, "pose_at") and not getattr(vehicle, "halted", False):
        poses = np.array([vehicle.pose_at(t_now_s + t) for t in times])
        return poses[:, 0], poses[:, 1], poses[:, 2]
    x, y, h = vehicle.world_pose()
    vx, vy = vehicle.world_velocity()
    return x + vx * times, y + vy * times, np.full_like(times, h)


def path_truth(instance: int, ego: EgoFuture, vehicle, actor_size_m, t_now_s: float) -> ActorTruth:
    """Truth of one actor from both exact futures (see the module docstring)."""
    times = ego.times
    actor = footprint_corners_many(*actor_future(vehicle, t_now_s, times), *actor_size_m)
    hit = footprints_overlap_many(ego.rects, actor)
    ttc = float(times[np.argmax(hit)]) if hit.any() else math.inf
    must = math.isfinite(ttc) and ego.speed_mps > 0 and bool(footprints_overlap_many(ego.braked, actor).any())
    heading = ego.pose[2]
    along = np.array([math.cos(heading), math.sin(heading)])
    rel = np.array(vehicle.world_pose()[:2]) - np.array(ego.pose[:2])
    lateral = float(rel @ np.array([-along[1], along[0]]))
    closing = ego.speed_mps - float(np.asarray(vehicle.world_velocity()) @ along)
    in_path = math.isfinite(ttc)
    ahead = in_path or float(rel @ along) > 0
    gap = closing * ttc if in_path else float(rel @ along) - ego.size_m[0] / 2
    return ActorTruth(instance, float(gap), lateral, float(closing), ttc, in_path, bool(ahead), must)
