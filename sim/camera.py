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

Two views of one sensor: the **wide** view is the camera as configured; the **fovea**
(``fovea_zoom`` Z) is a second pinhole with the same optical centre, the same
orientation and the same height, ``fovea_width_share`` of the width (default half: only
the road ahead matters at that magnification), focal length x Z, its principal point
placed so that the ego's road-forward direction (the horizon point straight ahead, at the
nominal pitch) falls on its centre pixel. It is exactly the crop of a Z-times-larger sensor: a
3D point at wide pixel (u, v) lies at fovea pixel

    u_f = Z (u - cx) + cx_f,    v_f = Z (v - cy) + cy_f

(``fovea_from_wide``; checked in ``tests/test_fovea.py``). Its frustum is off-axis
(``Pinhole.projection_matrix_gl``), and rendering it costs one more image of at most the
same pixel count, not Z^2 more.
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
MAX_FOVEA_ZOOM = 16.0  # [-] a larger zoom sees under 2 deg at the default 30 deg
#: [-] the fovea's width over the wide view's: at zoom 4 a 144 px fovea beside a 288 px wide view
#: spans +-5.7 deg, the ego's corridor (+-1.45 m with its margin) from 15 m on, and costs half a
#: full-width view's pixels; a third (96 px) alarms falsely on a car passing at its edge (docs/fovea.md)
DEFAULT_FOVEA_WIDTH_SHARE = 0.5
VIEWS = ("wide", "fovea")


def check_fovea_zoom(zoom) -> float | None:
    """None (no fovea) or a finite zoom in [1, MAX_FOVEA_ZOOM]; anything else is refused by value."""
    if zoom is None:
        return None
    if isinstance(zoom, bool) or not isinstance(zoom, (int, float)) or not math.isfinite(zoom):
        raise ValueError(f"fovea zoom {zoom!r}: must be a finite number in [1, {MAX_FOVEA_ZOOM:g}] (or off)")
    if not 1.0 <= zoom <= MAX_FOVEA_ZOOM:
        raise ValueError(f"fovea zoom {zoom!r}: must lie in [1, {MAX_FOVEA_ZOOM:g}] (or off)")
    return float(zoom)


@dataclass(frozen=True)
class Pinhole:
    """One view: image size and intrinsics [px] (pixel centres at integers), clipping planes [m]."""

    height_px: int
    width_px: int
    fx_px: float
    fy_px: float
    cx_px: float
    cy_px: float
    near_m: float
    far_m: float

    def K(self) -> np.ndarray:
        return np.array([[self.fx_px, 0, self.cx_px], [0, self.fy_px, self.cy_px], [0, 0, 1.0]])

    def intrinsics(self) -> np.ndarray:
        """(fx, fy, cx, cy) [px]."""
        return np.array([self.fx_px, self.fy_px, self.cx_px, self.cy_px])

    def project(self, p_cam: np.ndarray) -> np.ndarray:
        """(N, 3) OpenCV camera points -> (N, 2) pixels (u, v)."""
        p = np.atleast_2d(np.asarray(p_cam, dtype=np.float64))
        return np.stack([self.fx_px * p[:, 0] / p[:, 2] + self.cx_px, self.fy_px * p[:, 1] / p[:, 2] + self.cy_px], 1)

    def projection_matrix_gl(self, scale: int = 1) -> list[float]:
        """OpenGL projection matrix (column-major, 16 floats) for PyBullet, off-axis where
        the principal point is not the image centre.

        ``scale`` is the render resolution over the output resolution: output pixel u
        covers render pixels s u .. s u + s - 1, so the render's principal point is
        s cx + (s - 1) / 2. TinyRenderer samples render pixel (i, r) (r counted from the
        bottom row) at NDC (2 i / W - 1, 2 r / H - 1), i.e. at its corner; the third column
        puts those samples at the pixel centres of these intrinsics (checked in
        ``tests/test_camera.py`` and ``tests/test_fovea.py``).
        """
        w, h = self.width_px * scale, self.height_px * scale
        cx = scale * self.cx_px + (scale - 1) / 2
        cy = scale * self.cy_px + (scale - 1) / 2
        n, fa = self.near_m, self.far_m
        P = np.array(
            [
                [2 * self.fx_px / self.width_px, 0, 1 - 2 * cx / w, 0],
                [0, 2 * self.fy_px / self.height_px, (2 * cy + 2 - h) / h, 0],
                [0, 0, (fa + n) / (n - fa), 2 * fa * n / (n - fa)],
                [0, 0, -1, 0],
            ]
        )
        return P.T.reshape(-1).tolist()

    def linear_depth(self, depth_buffer: np.ndarray) -> np.ndarray:
        """Depth Z along the optical axis [m] from PyBullet's non-linear depth buffer."""
        n, fa = self.near_m, self.far_m
        return (fa * n / (fa - (fa - n) * depth_buffer)).astype(np.float32)


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
    fovea_zoom: float | None = None  # [-] focal of the fovea over the wide view's; None: no fovea
    fovea_width_share: float = DEFAULT_FOVEA_WIDTH_SHARE  # [-] the fovea's width over the wide view's

    def __post_init__(self) -> None:
        object.__setattr__(self, "fovea_zoom", check_fovea_zoom(self.fovea_zoom))
        checks = {
            "height_px": self.height_px >= 8,
            "width_px": self.width_px >= 8,
            "vfov_deg": 1.0 <= self.vfov_deg <= 150.0,
            "fps_hz": self.fps_hz > 0,
            "mount_height_m": self.mount_height_m > 0,
            "near_m": 0 < self.near_m < self.far_m,
            "supersample": self.supersample in (1, 2, 3, 4),
            "jitter_deg": 0 <= self.jitter_deg <= 10,
            "fovea_width_share": isinstance(self.fovea_width_share, (int, float))
            and not isinstance(self.fovea_width_share, bool)
            and 0 < self.fovea_width_share <= 1
            and self.fovea_width_px >= 6,
        }
        for name, ok in checks.items():
            if not ok:
                raise ValueError(f"CameraConfig.{name} = {getattr(self, name)!r} is out of range")

    @property
    def dt_s(self) -> float:
        """Frame interval [s]."""
        return 1.0 / self.fps_hz

    @property
    def fovea_width_px(self) -> int:
        """[px] the fovea's width: ``fovea_width_share`` of the wide view's, rounded down to a
        multiple of 3 (the network's stem stride), the full width at share 1."""
        if self.fovea_width_share >= 1:
            return self.width_px
        return max(3 * int(self.width_px * self.fovea_width_share // 3), 3)

    @property
    def aspect(self) -> float:
        return self.width_px / self.height_px

    def intrinsics(self) -> np.ndarray:
        """(fx, fy, cx, cy) in px of the wide view at the output resolution (square pixels)."""
        return self.wide().intrinsics()

    def K(self) -> np.ndarray:
        return self.wide().K()

    def wide(self) -> Pinhole:
        """The wide view: centred principal point, vertical FOV ``vfov_deg``."""
        fy = 0.5 * self.height_px / math.tan(math.radians(self.vfov_deg) / 2)
        h, w = self.height_px, self.width_px
        return Pinhole(h, w, fy, fy, (w - 1) / 2, (h - 1) / 2, self.near_m, self.far_m)

    def fovea(self) -> Pinhole | None:
        """The fovea (None without ``fovea_zoom``): focal x Z, centred on the horizon point
        straight ahead at the nominal pitch (see the module docstring)."""
        if self.fovea_zoom is None:
            return None
        z, wide = self.fovea_zoom, self.wide()
        f = z * wide.fy_px
        cy = (self.height_px - 1) / 2 + f * math.tan(math.radians(self.pitch_deg))
        w = self.fovea_width_px
        return Pinhole(self.height_px, w, f, f, (w - 1) / 2, cy, self.near_m, self.far_m)

    def view(self, name: str) -> Pinhole:
        """'wide' or 'fovea' (refused when this camera has none)."""
        if name == "wide":
            return self.wide()
        if name == "fovea" and self.fovea_zoom is not None:
            return self.fovea()
        raise ValueError(f"camera view {name!r}: this camera has {', '.join(self.view_names)}")

    @property
    def view_names(self) -> tuple[str, ...]:
        """The views rendered every frame: ('wide',) or ('wide', 'fovea')."""
        return VIEWS if self.fovea_zoom is not None else VIEWS[:1]

    def fovea_from_wide(self, uv_wide: np.ndarray) -> np.ndarray:
        """(N, 2) wide pixels -> (N, 2) fovea pixels of the same rays (the crop mapping)."""
        wide, fov = self.wide(), self.fovea()
        if fov is None:
            raise ValueError("fovea_from_wide: this camera has no fovea (fovea_zoom is None)")
        uv = np.atleast_2d(np.asarray(uv_wide, dtype=np.float64))
        z = self.fovea_zoom
        return np.stack([z * (uv[:, 0] - wide.cx_px) + fov.cx_px, z * (uv[:, 1] - wide.cy_px) + fov.cy_px], 1)

    def projection_matrix_gl(self, scale: int = 1) -> list[float]:
        """The wide view's OpenGL projection matrix (see ``Pinhole.projection_matrix_gl``)."""
        return self.wide().projection_matrix_gl(scale)

    def linear_depth(self, depth_buffer: np.ndarray) -> np.ndarray:
        """Depth Z along the optical axis [m] from PyBullet's non-linear depth buffer."""
        return self.wide().linear_depth(depth_buffer)


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
