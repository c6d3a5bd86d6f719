"""Stepping and capture shared by the scenario simulator and the random-scene generator.

Time: the traffic is integrated at ``SIM_DT_S`` (100 Hz) or the nearest step that divides
the camera's frame interval; a frame is captured after every ``n_sub`` steps. Poses are
highway-env world poses (x [m], y [m], heading [rad]; z up, x along the road).
"""

from __future__ import annotations

import numpy as np

from sim.camera import CameraConfig, Pinhole, cam_T_ego
from sim.ground_truth import GroundTruth, body_motions, camera_pose, compute_ground_truth, part_motions

SIM_DT_S = 0.01  # traffic integration step [s]

Pose = tuple[float, float, float]  # x [m], y [m], heading [rad]


def substeps(frame_dt_s: float) -> tuple[int, float]:
    """(steps per frame, step [s]): the step nearest ``SIM_DT_S`` that divides ``frame_dt_s``."""
    n_sub = max(1, int(round(frame_dt_s / SIM_DT_S)))
    return n_sub, frame_dt_s / n_sub


def step_traffic(road, ego, scripted, decel_mps2: float, t_s: float, dt_s: float) -> None:
    """One traffic step: the ego's brake command [m/s^2], each scripted vehicle's command at
    time ``t_s`` [s], then every vehicle on the highway-env ``road`` integrated by ``dt_s``."""
    ego.command(decel_mps2, dt_s)
    for veh in scripted:
        veh.command(t_s, dt_s)
    for veh in road.vehicles:
        veh.step(dt_s)


def capture_pose(camera: CameraConfig, rng: np.random.Generator, ego_pose: Pose) -> np.ndarray:
    """cam_T_world (4x4) of a frame: the mount of ``camera`` on the ego at ``ego_pose``, with
    a mount jitter [deg] drawn from ``rng`` when ``camera.jitter_deg`` > 0 (nothing drawn else)."""
    jitter = tuple(rng.normal(0.0, camera.jitter_deg, 3)) if camera.jitter_deg > 0 else (0.0, 0.0, 0.0)
    return camera_pose(cam_T_ego(camera, jitter), ego_pose)


def pair_ground_truth(
    view: Pinhole,
    depth_m: np.ndarray,
    instance: np.ndarray,
    cam_T_world: np.ndarray,
    prev_cam_T_world: np.ndarray,
    poses: dict[int, Pose],
    prev_poses: dict[int, Pose],
    dt_s: float,
    parts: np.ndarray | None = None,
    part_poses: dict[int, np.ndarray] | None = None,
    prev_part_poses: dict[int, np.ndarray] | None = None,
) -> GroundTruth:
    """Exact ground truth of the latest frame seen through ``view`` (its depth, instances
    and pose) against the previous one, ``dt_s`` [s] earlier; actors' motions from their
    poses in both frames. Both views of a camera share its pose, so the wide view and the
    fovea get their maps from this same code. Road users' rigid parts move with their own
    motions: ``parts`` (the render's part ids) and each part's world_T_part (4x4) in both
    frames (``sim.vru.part_poses``)."""
    motions = body_motions(prev_poses, poses)
    if parts is not None:
        motions.update(part_motions(prev_part_poses or {}, part_poses or {}))
    return compute_ground_truth(
        depth_m, instance, view.K(), cam_T_world, prev_cam_T_world, motions, dt_s, view.far_m, parts=parts
    )


def captures_ground_truth(view: Pinhole, depth_m, instance, parts, latest, prev) -> GroundTruth:
    """``pair_ground_truth`` of two captures (``sim.episode_records.Frame``: time, pose,
    actors' and parts' poses), ``latest`` seen through ``view`` with its render's
    ``depth_m``, ``instance`` and ``parts`` (any pinhole from the same pose: a run's views,
    the KITTI export's native camera)."""
    return pair_ground_truth(
        view,
        depth_m,
        instance,
        latest.cam_T_world,
        prev.cam_T_world,
        latest.poses,
        prev.poses,
        latest.t_s - prev.t_s,
        parts,
        latest.part_poses,
        prev.part_poses,
    )
