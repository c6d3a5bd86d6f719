"""Contact between the ego and the actors of a run: their footprints' corners, the
smallest gap between footprints [m], the first actor whose footprint touches the ego's,
and whether every actor has been passed.

An actor here is anything with ``vehicle`` (a highway-env vehicle with ``world_pose()``)
and ``spec`` (its ``VehicleSpec``)."""

from __future__ import annotations

import math

import numpy as np

from sim.actor_truth import footprint_distance
from sim.vehicles import EGO_SIZE_M, VehicleSpec, footprint_corners, footprints_overlap


def vehicle_corners(veh, spec: VehicleSpec) -> np.ndarray:
    x, y, h = veh.world_pose()
    return footprint_corners(x, y, h, spec.length_m, spec.width_m)


def ego_corners(ego) -> np.ndarray:
    x, y, h = ego.world_pose()
    return footprint_corners(x, y, h, EGO_SIZE_M[0], EGO_SIZE_M[1])


def min_distance_m(ego, actors, below_m: float = math.inf) -> float:
    """Smallest footprint distance [m] from the ego to any actor; actors whose
    bounding circles are already further than ``below_m`` are skipped."""
    ex, ey, _ = ego.world_pose()
    ego_r = 0.5 * math.hypot(EGO_SIZE_M[0], EGO_SIZE_M[1])
    ego_fp = None
    best = math.inf
    for a in actors:
        ax, ay, _ = a.vehicle.world_pose()
        lower = math.hypot(ax - ex, ay - ey) - ego_r - 0.5 * math.hypot(a.spec.length_m, a.spec.width_m)
        if lower >= min(best, below_m):
            continue
        ego_fp = ego_corners(ego) if ego_fp is None else ego_fp
        best = min(best, footprint_distance(ego_fp, vehicle_corners(a.vehicle, a.spec)))
    return best


def touching_actor(ego, actors):
    """The first actor whose footprint overlaps the ego's, or None."""
    ego_fp = ego_corners(ego)
    return next((a for a in actors if footprints_overlap(ego_fp, vehicle_corners(a.vehicle, a.spec))), None)


def all_passed(ego, actors) -> bool:
    """True when there are actors and each lies wholly behind the ego's rear (in the ego's
    frame, its heading now) and does not gain on it (its velocity along that heading at most
    the ego's speed): none can come back into the ego's path or its camera's view."""
    if not actors:
        return False
    x, y, h = ego.world_pose()
    fwd = np.array([math.cos(h), math.sin(h)])
    rear = -EGO_SIZE_M[0] / 2
    for a in actors:
        ahead = (vehicle_corners(a.vehicle, a.spec) - (x, y)) @ fwd
        if ahead.max() >= rear or float(a.vehicle.world_velocity() @ fwd) > float(ego.speed) + 1e-6:
            return False
    return True
