"""Who takes part in a scenario run, and where each starts: scripted vehicles (placed by
headway, or timed to meet the ego's path at a junction), road users (``sim.walkers``)
and the parked cars that hide them.

World coordinates: x [m] ahead of the ego's start, y [m] to its left, heading [rad].
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from scenarios.paths import EgoPath, crossing_lane, meet_start
from scenarios.spec import ActorSpec, ScenarioCase, VruActorSpec
from scenarios.vru_spec import STOP_DECEL_MPS2, vru_placement
from sim.actor_truth import ActorTruth, actor_truth
from sim.episode_placement import actor_placement, overlap_offset_m
from sim.path_truth import EgoFuture, path_truth
from sim.vehicles import EGO_SIZE_M, VehicleSpec
from sim.vru import VruSpec
from sim.walkers import Walker

OBSTRUCTION_GAP_M = 1.0  # [m] parked cars stand this far from the ego's path, and from the crossing line


@dataclass
class Actor:
    """One actor of a run: its instance id, body spec (``VehicleSpec`` or ``VruSpec``), the
    object that moves it (a highway-env vehicle or a ``Walker``), and for a road user the
    part id of each of its rigid parts (``sim.world.World.add_vru``)."""

    instance: int
    spec: VehicleSpec | VruSpec
    vehicle: object
    initial_speed_mps: float
    part_ids: list[int] = field(default_factory=list)

    @property
    def is_vru(self) -> bool:
        return isinstance(self.spec, VruSpec)


def conflict_placement(
    a: ActorSpec, spec: VehicleSpec, v_ego: float, path: EgoPath, road
) -> tuple[float, float, float]:
    """Start (x, y, heading) of a car timed by ``offset_s``: its centre passes the first
    point where its lane's centreline meets the ego's path ``offset_s`` before the ego's
    centre does (0: they meet)."""
    if a.direction in ("from_left", "from_right"):
        x_line, heading = crossing_lane(a.direction, road)
        point = (x_line, 0.0)
    else:
        heading = 0.0 if a.direction == "same" else math.pi
        point = (0.0, road.lane_center_y_m(a.lane) + overlap_offset_m(a.overlap_pct, spec.width_m))
    s_meet = path.first_crossing_s(point, heading, max_s_m=500.0)
    if s_meet is None:
        raise ValueError(f"a {a.direction} car in lane {a.lane} never meets the ego's {path.turn} path: give a headway")
    mx, my, _ = path.pose_at(s_meet)
    x, y = meet_start((mx, my), heading, a.speed_kph / 3.6, s_meet / v_ego - a.offset_s)
    return x, y, heading


def vehicle_start(a: ActorSpec, spec: VehicleSpec, v_ego: float, case: ScenarioCase) -> tuple[float, float, float]:
    if a.offset_s is not None:
        return conflict_placement(a, spec, v_ego, case.path, case.road)
    return actor_placement(a, spec, v_ego, case.road)


def walker_for(a: VruActorSpec, spec: VruSpec, v_ego: float, conflict_s: float) -> Walker:
    p = vru_placement(a, v_ego, conflict_s)
    return Walker(
        p.x_m,
        p.y_m,
        p.heading_rad,
        p.speed_mps,
        spec.length_m,
        spec.width_m,
        start_s=p.start_s,
        stop_after_m=p.stop_after_m,
        stop_decel_mps2=STOP_DECEL_MPS2,
    )


def obstruction_poses(a: VruActorSpec, v_ego: float, conflict_s: float, car_m: tuple[float, float]):
    """(x, y, heading) of the two parked cars that hide a crossing road user: on its side,
    ``OBSTRUCTION_GAP_M`` from the ego's path, one on each side of its crossing line."""
    p = vru_placement(a, v_ego, conflict_s)
    length, width = car_m
    side = -1.0 if a.path == "nearside" else 1.0
    y = side * (EGO_SIZE_M[1] / 2 + OBSTRUCTION_GAP_M + width / 2)
    x_line = p.crossing_x_m
    half = a.footprint_m[1] / 2 + OBSTRUCTION_GAP_M + length / 2
    return [(x_line - half, y, 0.0), (x_line + half, y, 0.0)]


def actor_truths(sim) -> list[ActorTruth]:
    """Every actor's truth in scenario run ``sim`` (``sim.episode.ScenarioSim``): from both
    exact futures where paths cross (``sim.path_truth``), else along the straight road
    (``sim.actor_truth``)."""
    ego_pose = sim.ego.world_pose()
    if sim.case.open_paths:  # contact from both exact futures (sim.path_truth)
        ego = EgoFuture(sim.path, ego_pose, EGO_SIZE_M[:2], float(sim.ego.speed))
        return [path_truth(a.instance, ego, a.vehicle, (a.spec.length_m, a.spec.width_m), sim.t_s) for a in sim.actors]
    return [
        actor_truth(
            a.instance,
            ego_pose,
            EGO_SIZE_M[:2],
            float(sim.ego.speed),
            a.vehicle.world_pose(),
            (a.spec.length_m, a.spec.width_m),
            a.vehicle.world_velocity(),
        )
        for a in sim.actors
    ]
