"""Pedestrians and cyclists in a random scene (``vru_share``): the scene's road gains
sidewalks, and 1-``MAX_VRUS`` road users cross it, walk or ride along it, or stand, near
and far. Every draw comes from the sample's Generator after the vehicles', so scenes
without road users keep their bytes.

World coordinates: x [m] ahead of the ego, y [m] to its left, heading [rad].
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from sim.random_scene_draw import SceneDraw
from sim.vru import vru_spec
from sim.walkers import Walker

MAX_VRUS = 5
VRU_KINDS = ("adult", "adult", "child", "cyclist", "cyclist")
VRU_MOTIONS = ("crossing", "crossing", "along", "standing")
VRU_EGO_SPEED_MPS = (0.0, 70 / 3.6)  # [m/s]
X_RANGE_M = (4.0, 50.0)  # [m] ahead of the ego
FOVEA_X_RANGE_M = (15.0, 90.0)  # [m] in a scene seen through the fovea
SPEED_MPS = {"adult": (0.6, 2.5), "child": (0.6, 3.0), "cyclist": (2.5, 7.0)}  # [m/s]
NEVER_S = 1e9  # [s] a standing road user's start time


def vru_scene(rng: np.random.Generator, scene: SceneDraw) -> SceneDraw:
    """The scene on a road with sidewalks (no barriers), at a town speed unless it is a fovea scene."""
    road = replace(scene.road, sidewalk_m=float(rng.uniform(2.0, 4.0)), barrier=False)
    v_ego = scene.v_ego if scene.fovea else float(rng.uniform(*VRU_EGO_SPEED_MPS))
    return replace(scene, road=road, v_ego=v_ego)


def draw_vru(rng: np.random.Generator, scene: SceneDraw, kind: str):
    """(x, y, heading, speed, start_s, motion) of one road user."""
    road = scene.road
    sw = road.sidewalk_m
    x = float(rng.uniform(*(FOVEA_X_RANGE_M if scene.fovea else X_RANGE_M)))
    speed = float(rng.uniform(*SPEED_MPS[kind]))
    motion = str(rng.choice(VRU_MOTIONS))
    side = float(rng.choice([-1.0, 1.0]))
    if motion == "crossing":
        y = float(rng.uniform(road.y_right_edge_m - sw, road.y_left_edge_m + sw))
        heading = side * math.pi / 2 + float(rng.normal(0.0, 0.2))
        return x, y, heading, speed, 0.0, motion
    edge = road.y_left_edge_m if side > 0 else road.y_right_edge_m
    y = edge + side * float(rng.uniform(-1.5, sw))  # near the kerb: on the road's edge or the sidewalk
    heading = float(rng.choice([0.0, math.pi])) + float(rng.normal(0.0, 0.05))
    return x, y, heading, speed, NEVER_S if motion == "standing" else 0.0, motion


def place_vrus(rng: np.random.Generator, world, scene: SceneDraw) -> list:
    """-> [(instance, spec, walker, motion, part ids, gait offset [m])] of 1-MAX_VRUS road users."""
    out = []
    for _ in range(int(rng.integers(1, MAX_VRUS + 1))):
        kind = str(rng.choice(VRU_KINDS))
        spec = vru_spec(kind, rng)
        x, y, heading, speed, start_s, motion = draw_vru(rng, scene, kind)
        walker = Walker(x, y, heading, speed, spec.length_m, spec.width_m, start_s=start_s)
        instance, part_ids = world.add_vru(spec)
        out.append((instance, spec, walker, motion, part_ids, float(rng.uniform(0.0, 2.0))))
    return out
