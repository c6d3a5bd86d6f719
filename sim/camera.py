"""Pinhole ego camera: configuration, intrinsics and the matrices PyBullet wants.

Convention:
    World frame ``W``: z up, x along the road (the ego's direction of travel), y to the
    left. highway-env's planar frame has y to the right; see :mod:`sim.traffic`.
    Ego frame ``E``: origin on the ground under the centre of the ego's footprint,
    x forward, y left, z up.
    Camera frame ``C`` (OpenCV): x right, y down, z forward along the optical axis.
    Pixel coordinates: (u, v) = (column, row); pixel centres at integer coordinates,
    so the principal point of a centred camera is ((W - 1) / 2, (H - 1) / 2).
    ``cam_T_world`` maps homogeneous world points to camera points.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

# OpenGL camera (x right, y up, z backward) from OpenCV camera (x right, y down, z forward).
GL_FROM_CV = np.diag([1.0, -1.0, -1.0, 1.0])
# Camera axes (OpenCV) expressed in the ego frame at zero pitch/yaw/roll:
# x_cam = -y_ego, y_cam = -z_ego, z_cam = x_ego.
_CV_FROM_EGO_AXES = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]])


@dataclass(frozen=True)
class CameraConfig:
    """Ego camera mounting and image format.

    Defaults suit the network on a 2-core CPU: 96 x 288 px at 10 Hz.
    """

    height_px: int = 96
    width_px: int = 288
    vfov_deg: float = 30.0  # vertical field of view [deg]
    fps_hz: float = 10.0  # frame rate [Hz]
    mount_height_m: float = 1.3  # optical centre above the ground [m]
    mount_forward_m: float = 0.8  # optical centre ahead of the ego's footprint centre [m]
    pitch_deg: float = 2.0  # positive looks down [deg]
    near_m: float = 0.1  # near clipping plane [m]
    far_m: float = 400.0  # far clipping plane [m]
    supersample: int = 1  # render at this factor and average down (anti-aliasing)
    jitter_deg: float = 0.0  # std of per-frame pitch/yaw/roll jitter [deg]

    def __post_init__(self) -> None:
        checks = {
            "height_px": self.height_px >= 8,
            "width_px": self.width_px >= 8,
            "vfov_deg": 1.0 <= self.vfov_deg <= 150.0,
            "fps_hz": self.fps_hz > 0,
            "mount_height_m": self.mount_height_m > 0,
            "near_m": 0 < self.near_m < self.far_m,
            "supersample": self.supersample in (1, 2, 3, 4),
            "jitter_deg": 0 <= self.jitter_deg <= 10,
        }
        for name, ok in checks.items():
            if not ok:
                raise ValueError(f"CameraConfig.{name} = {getattr(self, name)!r} is out of range")

    @property
    def dt_s(self) -> float:
        """Frame interval [s]."""
        return 1.0 / self.fps_hz

    @property
    def aspect(self) -> float:
        return self.width_px / self.height_px

    def intrinsics(self) -> np.ndarray:
        """(fx, fy, cx, cy) in px at the output resolution (square pixels)."""
        fy = 0.5 * self.height_px / math.tan(math.radians(self.vfov_deg) / 2)
        return np.array([fy, fy, (self.width_px - 1) / 2, (self.height_px - 1) / 2])

    def K(self) -> np.ndarray:
        fx, fy, cx, cy = self.intrinsics()
        return np.array([[fx, 0, cx], [0, fy, cy], [0, 0, 1.0]])

    def projection_matrix_gl(self, scale: int = 1) -> list[float]:
        """OpenGL projection matrix (column-major, 16 floats) for PyBullet.

        ``scale`` is the render resolution over the output resolution. TinyRenderer
        samples each pixel at its corner; the half-pixel offsets in the third column
        move the samples to the pixel centres, so the intrinsics above are exact
        (checked in ``tests/test_camera.py``).
        """
        f = 1.0 / math.tan(math.radians(self.vfov_deg) / 2)
        n, fa = self.near_m, self.far_m
        w_px, h_px = self.width_px * scale, self.height_px * scale
        P = np.array(
            [
                [f / self.aspect, 0, 1.0 / w_px, 0],
                [0, f, 1.0 / h_px, 0],
                [0, 0, (fa + n) / (n - fa), 2 * fa * n / (n - fa)],
                [0, 0, -1, 0],
            ]
        )
        return P.T.reshape(-1).tolist()

    def linear_depth(self, depth_buffer: np.ndarray) -> np.ndarray:
        """Depth Z along the optical axis [m] from PyBullet's non-linear depth buffer."""
        n, fa = self.near_m, self.far_m
        return (fa * n / (fa - (fa - n) * depth_buffer)).astype(np.float32)


def rotation_xyz_deg(roll_deg: float, pitch_deg: float, yaw_deg: float) -> np.ndarray:
    """R = Rz(yaw) @ Ry(pitch) @ Rx(roll) in a z-up frame (angles in degrees)."""
    r, p, y = np.radians([roll_deg, pitch_deg, yaw_deg])
    Rx = np.array([[1, 0, 0], [0, math.cos(r), -math.sin(r)], [0, math.sin(r), math.cos(r)]])
    Ry = np.array([[math.cos(p), 0, math.sin(p)], [0, 1, 0], [-math.sin(p), 0, math.cos(p)]])
    Rz = np.array([[math.cos(y), -math.sin(y), 0], [math.sin(y), math.cos(y), 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


def cam_T_ego(cfg: CameraConfig, jitter_rpy_deg: tuple[float, float, float] = (0, 0, 0)) -> np.ndarray:
    """4x4 transform from the ego frame to the OpenCV camera frame.

    The camera looks along the ego's x axis, pitched down by ``cfg.pitch_deg`` (a
    positive pitch about the ego's y axis, which points left, tilts the view down),
    plus an optional (roll, pitch, yaw) jitter in degrees.
    """
    roll, dpitch, yaw = jitter_rpy_deg
    ego_R_cam_body = rotation_xyz_deg(roll, cfg.pitch_deg + dpitch, yaw)  # body axes x fwd
    ego_R_cv = ego_R_cam_body @ _CV_FROM_EGO_AXES.T
    ego_T_cam = np.eye(4)
    ego_T_cam[:3, :3] = ego_R_cv
    ego_T_cam[:3, 3] = [cfg.mount_forward_m, 0.0, cfg.mount_height_m]
    return np.linalg.inv(ego_T_cam)


def view_matrix_gl(cam_T_world: np.ndarray) -> list[float]:
    """OpenGL view matrix (column-major, 16 floats) from an OpenCV ``cam_T_world``."""
    return (GL_FROM_CV @ cam_T_world).T.reshape(-1).tolist()


def pixel_rays(cfg: CameraConfig) -> np.ndarray:
    """(H, W, 3) camera-frame rays with z = 1 through every pixel centre."""
    fx, fy, cx, cy = cfg.intrinsics()
    v, u = np.mgrid[0 : cfg.height_px, 0 : cfg.width_px].astype(np.float64)
    return np.stack([(u - cx) / fx, (v - cy) / fy, np.ones_like(u)], axis=-1)
