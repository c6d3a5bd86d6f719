"""Exact per-pixel ground truth from the known rigid motions (never from differencing depth).

Convention:
    Maps live in the LATEST frame's pixel grid (time t1); the previous frame is at
    t0 = t1 - dt_s. For the 3D point seen at each pixel:
      eta   = Z(t1) / Z(t0)  (motion-in-depth, camera-frame depth of the same point)
      tau_s = dt_s * eta / (1 - eta): time to contact measured from t1, the latest
              capture time (``bittc_core.ttc`` converts). Approaching: 0 < eta < 1,
              tau > 0; receding: eta > 1, tau < 0; eta == 1: tau = +inf.
      flow_px = (u1 - u0, v1 - v0): where the point is in the latest frame minus where
              it was in the previous one (so x_prev = x_latest - flow).
    ``valid`` is False for sky and for points behind the previous camera.
    eta within ETA_ONE_TOL of 1 is set to exactly 1 (tau = +inf), so the stored float32
    eta and tau agree; a point moving exactly
    with the camera otherwise gets a random sign from float rounding.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bittc_core.ttc import eta_to_tau

ETA_ONE_TOL = 1e-7  # below this |eta - 1| rounds to 1.0 in float32 anyway


@dataclass
class GroundTruth:
    """Per-pixel maps, all (H, W); flow is (H, W, 2)."""

    eta: np.ndarray  # float32
    tau_s: np.ndarray  # float32 [s], +inf where eta == 1
    depth_m: np.ndarray  # float32, Z(t1) [m]
    flow_px: np.ndarray  # float32 (u, v) [px]
    instance: np.ndarray  # int32: -1 sky, 0 static, >0 vehicle
    valid: np.ndarray  # bool


def compute_ground_truth(
    depth_m: np.ndarray,
    instance: np.ndarray,
    K: np.ndarray,
    cam1_T_world: np.ndarray,
    cam0_T_world: np.ndarray,
    motions: dict[int, np.ndarray],
    dt_s: float,
    far_m: float,
    parts: np.ndarray | None = None,
) -> GroundTruth:
    """Ground truth of the latest frame.

    Args:
        depth_m: (H, W) depth Z at t1 along the optical axis [m].
        instance: (H, W) instance ids of the latest render.
        K: 3x3 intrinsics (pixel centres at integers).
        cam1_T_world, cam0_T_world: OpenCV camera poses at t1 and t0 (4x4).
        motions: body id -> 4x4 ``world(t0) <- world(t1)`` rigid motion of that
            body, i.e. ``world_T_body(t0) @ inv(world_T_body(t1))``. Missing ids
            (static scenery, id 0) are static: the identity.
        dt_s: t1 - t0 [s].
        parts: (H, W) part ids of the latest render (``sim.world.Render.part``): the body
            each pixel moves with, when road users' limbs move on their own; None: each
            pixel moves with its instance.
    """
    H, W = depth_m.shape
    fx, fy, cx, cy = K[0, 0], K[1, 1], K[0, 2], K[1, 2]
    v1, u1 = np.mgrid[0:H, 0:W].astype(np.float64)
    Z1 = depth_m.astype(np.float64)
    P_c1 = np.stack([(u1 - cx) / fx * Z1, (v1 - cy) / fy * Z1, Z1, np.ones_like(Z1)], axis=-1)
    # One 4x4 per rigid body: cam0 <- world(t0) <- world(t1) <- cam1.
    world_T_cam1 = np.linalg.inv(cam1_T_world)
    static = cam0_T_world @ world_T_cam1
    idx = np.clip(instance if parts is None else parts, 0, None)
    P_c0 = P_c1 @ static.T  # static world (and sky, masked below)
    for k in np.unique(idx):
        if k > 0 and int(k) in motions:
            m = idx == k
            P_c0[m] = P_c1[m] @ (cam0_T_world @ motions[int(k)] @ world_T_cam1).T
    Z0 = P_c0[..., 2]
    valid = (instance >= 0) & (Z1 < far_m) & (Z0 > 1e-3)
    with np.errstate(divide="ignore", invalid="ignore"):
        eta = np.where(valid, Z1 / Z0, 1.0)
        u0 = fx * P_c0[..., 0] / Z0 + cx
        v0 = fy * P_c0[..., 1] / Z0 + cy
    eta[np.abs(eta - 1.0) < ETA_ONE_TOL] = 1.0  # rounding of an exactly co-moving point
    flow = np.stack([u1 - u0, v1 - v0], axis=-1)
    flow[~valid] = 0.0
    tau = eta_to_tau(eta, dt_s).astype(np.float32)
    tau[~valid] = np.inf
    return GroundTruth(
        eta=eta.astype(np.float32),
        tau_s=tau,
        depth_m=depth_m.astype(np.float32),
        flow_px=flow.astype(np.float32),
        instance=instance.astype(np.int32),
        valid=valid,
    )


def planar_pose(x_m: float, y_m: float, heading_rad: float) -> np.ndarray:
    """4x4 world_T_body of a body on flat ground."""
    c, s = np.cos(heading_rad), np.sin(heading_rad)
    T = np.eye(4)
    T[:2, :2] = [[c, -s], [s, c]]
    T[:2, 3] = [x_m, y_m]
    return T


def body_motions(poses_prev: dict, poses_latest: dict) -> dict[int, np.ndarray]:
    """instance -> ``world(t0) <- world(t1)`` motion from planar poses (x, y, heading)
    at both frames, as :func:`compute_ground_truth` takes it."""
    return {i: planar_pose(*poses_prev[i]) @ np.linalg.inv(planar_pose(*poses_latest[i])) for i in poses_latest}


def part_motions(parts_prev: dict, parts_latest: dict) -> dict[int, np.ndarray]:
    """part id -> ``world(t0) <- world(t1)`` motion from the world_T_part (4x4) of both frames."""
    return {k: parts_prev[k] @ np.linalg.inv(T) for k, T in parts_latest.items() if k in parts_prev}


def camera_pose(cam_T_ego_: np.ndarray, ego_pose: tuple[float, float, float]) -> np.ndarray:
    """OpenCV ``cam_T_world`` of a camera mounted by ``cam_T_ego_`` on an ego at (x, y, heading)."""
    return cam_T_ego_ @ np.linalg.inv(planar_pose(*ego_pose))
