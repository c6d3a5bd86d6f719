"""Exact per-actor ground truth: bumper gap, lateral offset, closing speed, TTC.

Convention: straight road along world x. For an actor ahead of the ego, the gap is
the distance along x between the ego's front bumper plane and the nearest x-extent of
the actor's footprint; the closing speed is v_ego,x - v_actor,x; TTC = gap / closing
speed when closing (> 0), +inf when the gap opens. The actor is *in path* when its
footprint's y-extent overlaps the ego's (the ego keeps its lane, so its path is the
strip of its own width). This TTC is bumper to bumper; the per-pixel TTC of
:mod:`sim.ground_truth` is measured from the camera plane instead.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sim.vehicles import footprints_overlap


@dataclass(frozen=True)
class ActorTruth:
    instance: int
    gap_m: float  # bumper-to-bumper gap along the road [m]; negative once alongside/behind
    lateral_offset_m: float  # actor centre minus ego centre along world y [m] (+ = left)
    closing_speed_mps: float  # [m/s], > 0 when the gap shrinks
    ttc_s: float  # [s], +inf when not closing or not ahead
    in_path: bool
    ahead: bool
    must_brake: bool = False  # open paths only: contact follows even with full braking from shortly after now


def half_extents_xy(length_m: float, width_m: float, heading_rad: float) -> tuple[float, float]:
    """Half extents [m] of an oriented footprint's bounding box along world x and y."""
    c, s = abs(math.cos(heading_rad)), abs(math.sin(heading_rad))
    return 0.5 * (length_m * c + width_m * s), 0.5 * (length_m * s + width_m * c)


def actor_truth(
    instance: int,
    ego_xy_heading: tuple[float, float, float],
    ego_size_m: tuple[float, float],
    ego_speed_mps: float,
    actor_xy_heading: tuple[float, float, float],
    actor_size_m: tuple[float, float],
    actor_velocity_mps: np.ndarray,
) -> ActorTruth:
    ex, ey, _ = ego_xy_heading
    ax, ay, ah = actor_xy_heading
    ehx, ehy = ego_size_m[0] / 2, ego_size_m[1] / 2
    ahx, ahy = half_extents_xy(actor_size_m[0], actor_size_m[1], ah)
    ahead = ax > ex
    gap = (ax - ahx) - (ex + ehx) if ahead else (ex - ehx) - (ax + ahx)
    closing = ego_speed_mps - float(actor_velocity_mps[0]) if ahead else float(actor_velocity_mps[0]) - ego_speed_mps
    in_path = abs(ay - ey) < ehy + ahy
    ttc = gap / closing if (ahead and closing > 1e-9 and gap > 0) else math.inf
    return ActorTruth(instance, float(gap), float(ay - ey), float(closing), float(ttc), bool(in_path), bool(ahead))


def footprint_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Smallest distance [m] between two convex footprints (0 when they overlap)."""
    if footprints_overlap(a, b):
        return 0.0
    best = math.inf
    for P, Q in ((a, b), (b, a)):
        starts, ends = Q, np.roll(Q, -1, axis=0)
        d = ends - starts
        for p in P:
            t = np.clip(np.einsum("ij,ij->i", p - starts, d) / np.einsum("ij,ij->i", d, d), 0, 1)
            best = min(best, float(np.min(np.linalg.norm(starts + t[:, None] * d - p, axis=1))))
    return best
