"""The parameters of a random scene, drawn first from the sample's Generator: the camera's
mounting, the road, the ego's speed and braking, and whether the scene has a braking case
ahead or is seen through the fovea."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from sim.camera import CameraConfig
from sim.fovea_scene import FOVEA_EGO_SPEED_MPS, fovea_camera
from sim.scenery import RoadConfig

EGO_MAX_SPEED_MPS = 130 / 3.6  # [m/s]
AHEAD_EGO_SPEED_MPS = (10 / 3.6, EGO_MAX_SPEED_MPS)  # ego speed of a scene with a braking case ahead [m/s]


@dataclass(frozen=True)
class SceneDraw:
    """What is drawn of a scene before its world and actors."""

    camera: CameraConfig
    road: RoadConfig
    v_ego: float  # [m/s]
    ego_decel: float  # [m/s^2]
    ahead: bool  # a braking case ahead
    fovea: bool = False  # seen through the camera's fovea (sim.fovea_scene)
    vrus: bool = False  # with pedestrians and cyclists (sim.random_vrus)


def random_camera(rng: np.random.Generator, base: CameraConfig) -> CameraConfig:
    """Jitter the mounting: height, pitch, vertical FOV and per-frame rotation noise."""
    return replace(
        base,
        mount_height_m=float(rng.uniform(1.1, 1.8)),
        pitch_deg=float(rng.uniform(-1.0, 5.0)),
        vfov_deg=float(rng.uniform(24.0, 40.0)),
        jitter_deg=float(rng.uniform(0.0, 0.4)),
    )


def random_road(rng: np.random.Generator) -> RoadConfig:
    return RoadConfig(
        lanes_left=int(rng.integers(0, 4)),
        lanes_right=int(rng.integers(0, 3)),
        lane_width_m=float(rng.uniform(3.0, 3.8)),
        x_start_m=-20.0,
        x_end_m=160.0,
        markings_max_x_m=90.0,
        roadside_spacing_m=float(rng.uniform(12.0, 35.0)),
        barrier=bool(rng.random() < 0.6),
        buildings=bool(rng.random() < 0.8),
    )


def draw_scene(
    rng: np.random.Generator, base_camera: CameraConfig, ahead_share: float, fovea_share: float
) -> SceneDraw:
    camera = random_camera(rng, base_camera)
    road = random_road(rng)
    v_ego = 0.0 if rng.random() < 0.08 else float(rng.uniform(0.0, EGO_MAX_SPEED_MPS))
    ego_decel = float(rng.uniform(2.0, 7.0)) if rng.random() < 0.1 else 0.0
    ahead = ahead_share > 0 and rng.random() < ahead_share
    if ahead:
        v_ego = float(rng.uniform(*AHEAD_EGO_SPEED_MPS))
    fovea = fovea_share > 0 and rng.random() < fovea_share  # drawn only when asked: old datasets keep their bytes
    if fovea:
        camera, ahead = fovea_camera(rng, camera), False
        v_ego = float(rng.uniform(*FOVEA_EGO_SPEED_MPS))
    return SceneDraw(camera, road, v_ego, ego_decel, ahead, fovea)
