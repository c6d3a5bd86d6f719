"""Randomised scenes for training data: a road, an ego, 0-12 actors, a short clip.

Everything is drawn from one numpy Generator seeded by the sample's seed, so a
(dataset seed, sample seed) pair fixes every byte of the clip, whichever process
renders it. Ground truth follows :mod:`sim.ground_truth` (maps in the latest frame's
grid, tau from the latest frame's capture time).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sim.camera import CameraConfig
from sim.ground_truth import GroundTruth
from sim.random_actors import (
    AHEAD_CLASSES,
    AHEAD_MAX_OTHER_ACTORS,
    AHEAD_MOTIONS,
    AHEAD_OVERLAP,
    AHEAD_TTC_RANGE_S,
    CLASSES,
    MAX_ACTORS,
    MOTIONS,
    TTC_RANGE_S,
    X_RANGE_M,
    place_actors,
)
from sim.random_clip_frames import clip_meta, render_frames
from sim.random_scene_draw import AHEAD_EGO_SPEED_MPS, EGO_MAX_SPEED_MPS, draw_scene, random_camera, random_road
from sim.random_vrus import place_vrus, vru_scene
from sim.stepping import pair_ground_truth, substeps
from sim.textures import TextureBank
from sim.traffic import ActuatorConfig, EgoVehicle, build_road
from sim.vehicles import EGO_SIZE_M
from sim.world import World

__all__ = [
    "AHEAD_CLASSES",
    "AHEAD_EGO_SPEED_MPS",
    "AHEAD_MAX_OTHER_ACTORS",
    "AHEAD_MOTIONS",
    "AHEAD_OVERLAP",
    "AHEAD_TTC_RANGE_S",
    "CLASSES",
    "EGO_MAX_SPEED_MPS",
    "MAX_ACTORS",
    "MOTIONS",
    "TTC_RANGE_S",
    "X_RANGE_M",
    "Clip",
    "random_camera",
    "random_road",
    "render_clip",
]


@dataclass
class Clip:
    """K frames and the ground truth of each consecutive pair.

    images: K arrays (H, W, 3) uint8, oldest first. gts[j] compares frame j+1 (latest)
    with frame j (previous). meta: JSON-serialisable description (intrinsics, dt,
    camera, ego and actor states per frame, scene parameters).
    """

    images: list[np.ndarray]
    gts: list[GroundTruth]
    meta: dict


def render_clip(
    sample_seed: int,
    base_camera: CameraConfig,
    clip_length: int,
    bank: TextureBank,
    world: World | None = None,
    ahead_share: float = 0.0,
    fovea_share: float = 0.0,
    vru_share: float = 0.0,
) -> Clip:
    """Draw a scene from ``sample_seed`` and render ``clip_length`` frames of it.

    ``world``: a world built on ``bank`` to rebuild in place (``World.reset``) instead of
    building and closing a new one; the clip's bytes are the same either way.
    ``ahead_share``: the probability that the scene also has a braking case ahead
    (``sim.random_actors.ahead_actor``; the ego then drives at 10-130 km/h, with at most
    ``AHEAD_MAX_OTHER_ACTORS`` random actors). At 0 nothing more is drawn, so the bytes
    are those of the datasets made before the option.
    ``fovea_share``: the probability that the scene is seen through a fovea instead
    (:mod:`sim.fovea_scene`: a far target in or near the ego's lane and look-alikes; the
    images, ground truth and intrinsics are the fovea's). At 0 nothing more is drawn.

    Steps, each drawing from the one ``rng`` in this order: the scene (camera, road, ego),
    the world, the actors, the frames; then the ground truth and the metadata.
    """
    if world is not None and world.bank is not bank:
        raise ValueError("render_clip: the world must use the given texture bank")
    rng = np.random.default_rng(sample_seed)
    scene = draw_scene(rng, base_camera, ahead_share, fovea_share)
    with_vrus = vru_share > 0 and rng.random() < vru_share  # drawn only when asked: old datasets keep their bytes
    if with_vrus:
        scene = vru_scene(rng, scene)
    hw_road = build_road(scene.road, seed=sample_seed % (2**31))
    n_sub, sim_dt = substeps(scene.camera.dt_s)
    ego = EgoVehicle(hw_road, 0.0, 0.0, scene.v_ego, EGO_SIZE_M[0], EGO_SIZE_M[1], ActuatorConfig(delay_s=0.0), sim_dt)
    hw_road.vehicles.append(ego)
    world_seed = int(rng.integers(2**31))
    owned = world is None
    if owned:
        world = World(scene.camera, scene.road, seed=world_seed, bank=bank)
    else:
        world.reset(scene.camera, scene.road, seed=world_seed)
    try:
        actors = place_actors(rng, world, hw_road, scene)
        vrus = place_vrus(rng, world, scene) if with_vrus else []
        view = scene.camera.fovea() if scene.fovea else scene.camera.wide()
        images, frames, states = render_frames(
            rng, world, hw_road, ego, actors, scene, clip_length, n_sub, sim_dt, view, vrus
        )
        gts = [
            pair_ground_truth(view, r1.depth_m, r1.instance, c1, c0, p1, p0, scene.camera.dt_s, r1.part, q1, q0)
            for (_, c0, p0, q0), (r1, c1, p1, q1) in zip(frames[:-1], frames[1:])
        ]
    finally:
        if owned:
            world.close()
    return Clip(images, gts, clip_meta(sample_seed, scene, view, actors, states, vrus))
