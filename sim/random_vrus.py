"""Pedestrians and cyclists in a random scene (``vru_share``): the scene's road gains
sidewalks, at most ``sim.random_actors.VRU_MAX_VEHICLES`` random vehicles, and
2-``MAX_VRUS`` road users cross it (near the ego's path, their line at a TTC drawn from
``CROSSING_TTC_S`` at the ego's speed), walk or ride along it, or stand. Every draw
comes from the sample's Generator after the vehicles', so scenes without road users keep
their bytes.

World coordinates: x [m] ahead of the ego, y [m] to its left, heading [rad].
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from sim.random_scene_draw import SceneDraw
from sim.vru import vru_spec
from sim.walkers import Walker

MAX_VRUS = 6
VRU_KINDS = ("adult", "adult", "adult", "child", "child", "cyclist", "cyclist")
VRU_MOTIONS = ("crossing", "crossing", "along", "standing")
VRU_EGO_SPEED_MPS = (0.0, 70 / 3.6)  # [m/s]
X_RANGE_M = (4.0, 50.0)  # [m] ahead of the ego
FOVEA_X_RANGE_M = (15.0, 90.0)  # [m] in a scene seen through the fovea
SPEED_MPS = {"adult": (0.6, 2.5), "child": (0.6, 3.0), "cyclist": (2.5, 7.0)}  # [m/s]
NEVER_S = 1e9  # [s] a standing road user's start time
CROSSING_TTC_S = (0.4, 4.0)  # [s] a crossing road user's line lies this far ahead at the ego's speed, log-uniform
CROSSING_NEAR_M = 4.0  # [m] ... and it starts within this of the ego's path, or on it


def vru_scene(rng: np.random.Generator, scene: SceneDraw) -> SceneDraw:
    """The scene on a road with sidewalks (no barriers), at a town speed unless it is a fovea scene."""
    road = replace(scene.road, sidewalk_m=float(rng.uniform(2.0, 4.0)), barrier=False)
    v_ego = scene.v_ego if scene.fovea else float(rng.uniform(*VRU_EGO_SPEED_MPS))
    return replace(scene, road=road, v_ego=v_ego, vrus=True)


def draw_vru(rng: np.random.Generator, scene: SceneDraw, kind: str):
    """(x, y, heading, speed, start_s, motion) of one road user."""
    road = scene.road
    sw = road.sidewalk_m
    x = float(rng.uniform(*(FOVEA_X_RANGE_M if scene.fovea else X_RANGE_M)))
    speed = float(rng.uniform(*SPEED_MPS[kind]))
    motion = str(rng.choice(VRU_MOTIONS))
    side = float(rng.choice([-1.0, 1.0]))
    if motion == "crossing":  # what braking must judge: near the ego's path, at the TTCs that matter
        if not scene.fovea and scene.v_ego > 1.0:
            ttc = math.exp(rng.uniform(*np.log(CROSSING_TTC_S)))
            x = float(np.clip(scene.v_ego * ttc, X_RANGE_M[0], X_RANGE_M[1]))
        y = float(rng.uniform(-CROSSING_NEAR_M, CROSSING_NEAR_M))
        heading = side * math.pi / 2 + float(rng.normal(0.0, 0.2))
        return x, y, heading, speed, 0.0, motion
    edge = road.y_left_edge_m if side > 0 else road.y_right_edge_m
    y = edge + side * float(rng.uniform(-1.5, sw))  # near the kerb: on the road's edge or the sidewalk
    heading = float(rng.choice([0.0, math.pi])) + float(rng.normal(0.0, 0.05))
    return x, y, heading, speed, NEVER_S if motion == "standing" else 0.0, motion


def place_vrus(rng: np.random.Generator, world, scene: SceneDraw) -> list:
    """-> [(instance, spec, walker, motion, gait offset [m])] of 2-MAX_VRUS road users."""
    out = []
    for _ in range(int(rng.integers(2, MAX_VRUS + 1))):
        kind = str(rng.choice(VRU_KINDS))
        spec = vru_spec(kind, rng)
        x, y, heading, speed, start_s, motion = draw_vru(rng, scene, kind)
        walker = Walker(x, y, heading, speed, spec.length_m, spec.width_m, start_s=start_s)
        instance, _ = world.add_vru(spec)
        out.append((instance, spec, walker, motion, float(rng.uniform(0.0, 2.0))))
    return out
