"""Who is in a random scene: the braking case ahead or the fovea's target when the scene
has one, then random actors (or, in a fovea scene, the vehicles beside its target), each
placed clear of the ego and of the others. World coordinates: x [m] ahead of the ego,
y [m] to its left, heading [rad]."""

from __future__ import annotations

import math

import numpy as np

from sim.fovea_scene import FOVEA_CLASSES, FOVEA_MAX_OTHERS, fovea_other, fovea_target, threat_motion
from sim.random_scene_draw import SceneDraw
from sim.scenery import RoadConfig
from sim.traffic import ScriptedVehicle
from sim.vehicles import EGO_SIZE_M, footprint_corners, footprints_overlap, sample_spec
from sim.world import World

MOTIONS = ("approaching", "receding", "oncoming", "crossing", "lateral", "stationary", "braking", "following")
TTC_RANGE_S = (0.5, 20.0)  # closing actors are placed at a TTC drawn log-uniformly from this range [s]
X_RANGE_M = (6.0, 120.0)  # distance ahead of the ego [m]
CLASSES = ("car", "car", "car", "gvt", "van", "truck")
MAX_ACTORS = 12
# braking cases ahead (``ahead_share``): what a collision-warning camera must fence on time
AHEAD_MOTIONS = ("stationary", "slower", "braking")
AHEAD_CLASSES = ("gvt", "car", "van", "truck")
AHEAD_TTC_RANGE_S = (0.3, 4.0)  # [s] bumper-to-bumper TTC at the first frame, log-uniform
AHEAD_OVERLAP = (0.25, 1.0)  # |share of the ego's width overlapped|, either side (Euro NCAP: 50-100 %)
AHEAD_MAX_OTHER_ACTORS = 6
VRU_MAX_VEHICLES = 4  # random vehicles in a scene with pedestrians and cyclists


def actor_motion(rng: np.random.Generator, motion: str, road: RoadConfig, v_ego: float):
    """(x, y, heading, speed, accel, keep_lateral) for one actor."""
    lanes = list(range(-road.lanes_right, road.lanes_left + 1))
    lane_y = road.lane_center_y_m(int(rng.choice(lanes))) + float(rng.uniform(-0.4, 0.4))
    x = float(rng.uniform(*X_RANGE_M))
    heading, accel, keep = 0.0, 0.0, True
    if motion == "approaching":
        speed = max(0.0, v_ego - float(rng.uniform(1.0, 20.0)))
    elif motion == "receding":
        speed = v_ego + float(rng.uniform(1.0, 15.0))
    elif motion == "oncoming":
        heading, speed = math.pi, float(rng.uniform(3.0, 30.0))
    elif motion == "crossing":
        side = float(rng.choice([-1.0, 1.0]))
        heading = side * math.pi / 2 + float(rng.normal(0.0, 0.15))
        lane_y = -side * float(rng.uniform(0.0, road.y_left_edge_m + 8.0))
        x, speed, keep = float(rng.uniform(8.0, 60.0)), float(rng.uniform(1.0, 12.0)), False
    elif motion == "lateral":
        heading = float(rng.choice([-1.0, 1.0]) * rng.uniform(0.05, 0.3))
        speed, keep = max(0.0, v_ego + float(rng.uniform(-8.0, 8.0))), False
    elif motion == "stationary":
        speed = 0.0
    elif motion == "following":  # moves exactly like the ego: eta = 1, tau = inf
        speed = v_ego
    else:  # braking
        speed, accel = max(0.0, v_ego + float(rng.uniform(-5.0, 5.0))), -float(rng.uniform(2.0, 8.0))
    closing = v_ego - speed * math.cos(heading)
    if motion != "crossing" and closing < -0.5:  # opening gap: keep it near enough to cover pixels
        x = float(rng.uniform(X_RANGE_M[0], 50.0))
    if motion != "crossing" and closing > 0.5:
        # spread TTCs evenly on a log scale instead of letting near, fast actors dominate
        ttc = math.exp(rng.uniform(math.log(TTC_RANGE_S[0]), math.log(TTC_RANGE_S[1])))
        x = float(np.clip(ttc * closing, *X_RANGE_M))
    return x, lane_y, heading, speed, accel, keep


def ahead_actor(rng: np.random.Generator, v_ego: float, length_m: float, width_m: float):
    """(x, y, heading, speed, accel, motion) of a braking case ahead of the ego in its lane.

    Overlap O (share of the ego's width overlapped, Euro NCAP's definition for equal
    widths): the target's centre sits (1 - |O|) (w_ego + w_target) / 2 to the left
    (O > 0) or right (O < 0) of the ego's."""
    motion = str(rng.choice(AHEAD_MOTIONS))
    speed, accel = threat_motion(rng, motion, v_ego)
    ttc = math.exp(rng.uniform(math.log(AHEAD_TTC_RANGE_S[0]), math.log(AHEAD_TTC_RANGE_S[1])))
    gap = float(np.clip(ttc * max(v_ego - speed, 0.5), 2.0, X_RANGE_M[1]))
    overlap = float(rng.uniform(*AHEAD_OVERLAP)) * float(rng.choice([-1.0, 1.0]))
    y = math.copysign(1.0, overlap) * (1.0 - abs(overlap)) * (EGO_SIZE_M[1] + width_m) / 2
    return EGO_SIZE_M[0] / 2 + gap + length_m / 2, y, 0.0, speed, accel, f"ahead-{motion}"


def place_actors(rng, world: World, hw_road, scene: SceneDraw) -> list:
    """-> [(instance, spec, vehicle, motion)]: the braking case ahead (if drawn), then random
    actors placed clear of the ego and of each other (5 tries each)."""
    actors = []
    taken = [footprint_corners(0.0, 0.0, 0.0, EGO_SIZE_M[0] + 2.0, EGO_SIZE_M[1] + 1.0)]
    if scene.ahead or scene.fovea:
        spec = sample_spec(rng, str(rng.choice(FOVEA_CLASSES if scene.fovea else AHEAD_CLASSES)))
        draw = fovea_target if scene.fovea else ahead_actor
        x, y, heading, speed, accel, motion = draw(rng, scene.v_ego, spec.length_m, spec.width_m)
        taken.append(footprint_corners(x, y, heading, spec.length_m + 1.0, spec.width_m + 0.5))
        veh = ScriptedVehicle(hw_road, x, y, heading, speed, spec.length_m, spec.width_m, accel_mps2=accel)
        hw_road.vehicles.append(veh)
        actors.append((world.add_vehicle(spec), spec, veh, motion))
    if scene.fovea:
        _place_fovea_others(rng, world, hw_road, scene, taken, actors)
        return actors
    limit = AHEAD_MAX_OTHER_ACTORS if scene.ahead else VRU_MAX_VEHICLES if scene.vrus else MAX_ACTORS
    for _ in range(int(rng.integers(0, limit + 1))):
        motion = str(rng.choice(MOTIONS))
        spec = sample_spec(rng, str(rng.choice(CLASSES)))
        _place_clear(
            world, hw_road, taken, actors, spec, lambda m=motion: (*actor_motion(rng, m, scene.road, scene.v_ego), m)
        )
    return actors


def _place_clear(world: World, hw_road, taken: list, actors: list, spec, draw) -> None:
    """Place a vehicle of ``spec`` where ``draw()`` -> (x, y, heading, speed, accel, keep_lateral,
    motion) puts it clear of every footprint in ``taken`` (5 tries; none fits: not placed),
    appending its footprint to ``taken`` and (instance, spec, vehicle, motion) to ``actors``."""
    for _attempt in range(5):
        x, y, heading, speed, accel, keep, motion = draw()
        corners = footprint_corners(x, y, heading, spec.length_m + 1.0, spec.width_m + 0.5)
        if not any(footprints_overlap(corners, t) for t in taken):
            break
    else:
        return
    taken.append(corners)
    veh = ScriptedVehicle(
        hw_road, x, y, heading, speed, spec.length_m, spec.width_m, accel_mps2=accel, keep_lateral=keep
    )
    hw_road.vehicles.append(veh)
    actors.append((world.add_vehicle(spec), spec, veh, motion))


def _place_fovea_others(rng, world: World, hw_road, scene: SceneDraw, taken: list, actors: list) -> None:
    """Append 0-``FOVEA_MAX_OTHERS`` vehicles a fovea sees beside its target (adjacent,
    oncoming, another lead), each clear of the others (5 tries each)."""
    for _ in range(int(rng.integers(0, FOVEA_MAX_OTHERS + 1))):
        spec = sample_spec(rng, str(rng.choice(CLASSES)))

        def draw(spec=spec):
            x, y, heading, speed, motion = fovea_other(rng, scene.road, scene.v_ego, spec.length_m)
            return x, y, heading, speed, 0.0, True, motion

        _place_clear(world, hw_road, taken, actors, spec, draw)
