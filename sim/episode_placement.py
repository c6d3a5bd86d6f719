"""Where a scenario's scripted actor starts: its Euro NCAP-style headway, lane and overlap
turned into a world pose (x [m] forward, y [m] left, heading [rad]) at t = 0."""

from __future__ import annotations

import math

from scenarios.road import RoadConfig
from scenarios.spec import ActorSpec
from sim.vehicles import EGO_SIZE_M, VehicleSpec


def overlap_offset_m(overlap_pct: float, target_width_m: float, ego_width_m: float = EGO_SIZE_M[1]) -> float:
    """Lateral offset [m] of the target's centreline from the ego's (+ = left) for an
    overlap of ``overlap_pct``.

    Euro NCAP: the overlap is the share of the ego's (VUT's) width that overlaps the
    target, whatever the target's width; O < 0 puts the target on the ego's right. At
    +-50 % the target's near edge lies on the ego's centreline. At 100 % (or whenever the
    target is too narrow to cover the requested share) the centrelines are aligned.
    """
    shared_m = abs(overlap_pct) / 100.0 * ego_width_m
    if shared_m >= min(ego_width_m, target_width_m):
        return 0.0
    # the target's near edge lies ``shared_m`` inside the ego's far side
    return math.copysign((ego_width_m + target_width_m) / 2 - shared_m, overlap_pct)


def actor_placement(a: ActorSpec, spec: VehicleSpec, v_ego: float, road: RoadConfig) -> tuple[float, float, float]:
    """Initial (x, y, heading) of a scripted actor from Euro NCAP-style parameters; the ego
    starts at the origin, heading along +x at ``v_ego`` [m/s]."""
    gap = a.headway_m if a.headway_m is not None else a.headway_s * v_ego
    x = EGO_SIZE_M[0] / 2 + gap + spec.length_m / 2
    y = road.lane_center_y_m(a.lane) + overlap_offset_m(a.overlap_pct, spec.width_m)
    heading = 0.0 if a.direction == "same" else math.pi
    return x, y, heading
