"""A run's frames in the KITTI raw layout (``sim.kitti_raw``): image, lidar, calibration, timestamps.

``KittiExporter`` is a capture hook of the closed loop (``sim.loop.ClosedLoop``): every
captured frame is rendered again through a native camera of KITTI's sensor size
(375 x 1242 px) with the wide view's horizontal field of view, from the same pose, and
written with:

* a velodyne scan ray-cast from that render's exact depth: ``BEAMS`` beams spread linearly
  over ``ELEVATION_DEG`` (an HDL-64E's), every ``AZIMUTH_STEP_DEG`` across the camera's
  horizontal field of view (the depth exists only there). Each ray is snapped to the
  native pixel it passes through and the point placed on that pixel's ray at its depth, so
  every point lies exactly on the rendered surface. Sky and points beyond ``MAX_RANGE_M``
  return nothing. The velodyne frame sits at the camera's optical centre, level, x along
  the ego's heading (y left, z up); ``calib_velo_to_cam.txt`` holds that transform;
* with ``bittc run --realism``, the image through the run's sensor (``sim.sensor``): the
  same effects as the run's own views, moved by the exact flow of the native render since
  the previous capture, with noise from a stream of its own (the run's views keep their
  bytes) and a video codec of its own where the sensor has one;
* ``oxts`` with the ego's forward speed (vf, [m/s]);
* ``bittc_truth.csv``: per frame, the critical actor's camera-plane depth of its nearest
  face (bumper gap + the bumper's distance ahead of the camera) [m] and its camera-plane
  TTC (that depth / the closing speed) [s], empty where there is none or it is not closing.

The drive is written into a temporary folder beside the target and renamed at the end of
the run (``finish``); an aborted run leaves nothing (``abort``).
"""

from __future__ import annotations

import math
import shutil
import tempfile
from pathlib import Path

import cv2
import numpy as np

from sim import kitti_raw as kr
from sim.camera import CameraConfig, Pinhole
from sim.vehicles import EGO_SIZE_M

KITTI_HW = (375, 1242)  # [px] the sensor's image size
BEAMS = 64
ELEVATION_DEG = (2.0, -24.9)  # [deg] the top and bottom beams
AZIMUTH_STEP_DEG = 0.2  # [deg]
MAX_RANGE_M = 120.0  # [m]
TRUTH_FILE = "bittc_truth.csv"


def native_pinhole(camera: CameraConfig) -> Pinhole:
    """KITTI's sensor size with the wide view's horizontal field of view (square pixels,
    principal point centred): a 96x288 wide view at 30 deg vertical gives f = 772 px, a
    27 deg vertical field of view (KITTI's colour cameras: 721 px, 29 deg)."""
    h, w = KITTI_HW
    f = camera.wide().fx_px * w / camera.width_px
    return Pinhole(h, w, f, f, (w - 1) / 2, (h - 1) / 2, camera.near_m, camera.far_m)


def velo_to_cam(cam_T_world: np.ndarray) -> np.ndarray:
    """(4, 4) the level frame at the camera's optical centre (x along the camera's heading,
    z up) -> the OpenCV camera frame."""
    world_T_cam = np.linalg.inv(cam_T_world)
    forward = world_T_cam[:3, 2]
    yaw = math.atan2(forward[1], forward[0])
    world_T_velo = np.eye(4)
    world_T_velo[:3, :3] = [[math.cos(yaw), -math.sin(yaw), 0], [math.sin(yaw), math.cos(yaw), 0], [0, 0, 1]]
    world_T_velo[:3, 3] = world_T_cam[:3, 3]
    return cam_T_world @ world_T_velo


def beam_pixels(pin: Pinhole, v2c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """-> (rows, cols) of the native pixels the beams pass through (each pixel once)."""
    half = math.degrees(math.atan((pin.width_px / 2) / pin.fx_px))
    az = np.radians(np.arange(-half, half + 1e-9, AZIMUTH_STEP_DEG))
    el = np.radians(np.linspace(*ELEVATION_DEG, BEAMS))
    e, a = np.meshgrid(el, az, indexing="ij")
    d = np.stack([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)], -1).reshape(-1, 3)
    dc = d @ v2c[:3, :3].T
    ahead = dc[:, 2] > 1e-6
    u = np.round(pin.fx_px * dc[ahead, 0] / dc[ahead, 2] + pin.cx_px).astype(int)
    v = np.round(pin.fy_px * dc[ahead, 1] / dc[ahead, 2] + pin.cy_px).astype(int)
    inside = (u >= 0) & (u < pin.width_px) & (v >= 0) & (v < pin.height_px)
    flat = np.unique(v[inside] * pin.width_px + u[inside])
    return flat // pin.width_px, flat % pin.width_px


def scan_from_depth(depth_m: np.ndarray, instance: np.ndarray, pin: Pinhole, v2c, rows, cols) -> np.ndarray:
    """(N, 4) float32 velodyne points (x, y, z [m], reflectance) on the beams' pixels."""
    z = depth_m[rows, cols].astype(np.float64)
    ok = (instance[rows, cols] >= 0) & np.isfinite(z) & (z < pin.far_m)
    p_cam = np.stack([(cols - pin.cx_px) / pin.fx_px * z, (rows - pin.cy_px) / pin.fy_px * z, z], -1)[ok]
    ok_range = np.linalg.norm(p_cam, axis=1) <= MAX_RANGE_M
    cam_to_velo = np.linalg.inv(v2c)
    p = p_cam[ok_range] @ cam_to_velo[:3, :3].T + cam_to_velo[:3, 3]
    return np.concatenate([p, np.full((len(p), 1), 0.5)], 1).astype(np.float32)


class KittiExporter:
    """Capture hook writing a run in the KITTI raw layout into ``out`` (see the module docstring)."""

    def __init__(self, sim, out: str | Path) -> None:
        self.sim = sim
        self.out = Path(out)
        if self.out.exists() and (not self.out.is_dir() or any(self.out.iterdir())):
            raise kr.FootageError(f"KITTI export folder {str(self.out)!r}: exists and is not empty")
        self.tmp: Path | None = None  # made at the first frame, so a run that never starts leaves nothing
        self.pin = native_pinhole(sim.camera)
        self.bumper_ahead_m = EGO_SIZE_M[0] / 2 - sim.camera.mount_forward_m
        self.v2c = None
        self.times: list[float] = []
        self.truth: list[str] = []
        self.prev = None  # the previous capture (its poses), for the sensor's motion
        if sim.sensor is not None:
            from sim.sensor import EXPORT_NOISE_WORD, REALISM_STREAM, new_codec

            self.rng = np.random.default_rng([sim.seed, REALISM_STREAM, EXPORT_NOISE_WORD])
            self.codec = new_codec(sim.sensor)

    def __call__(self, rec, frame) -> None:
        i = len(self.times)
        if self.tmp is None:
            self.out.parent.mkdir(parents=True, exist_ok=True)
            self.tmp = Path(tempfile.mkdtemp(prefix=f".{self.out.name}-", dir=self.out.parent))
            for sub in (kr.IMAGES, kr.VELODYNE, kr.OXTS):
                (self.tmp / sub / "data").mkdir(parents=True)
        if self.v2c is None:
            self.v2c = velo_to_cam(frame.cam_T_world)
            self.rows, self.cols = beam_pixels(self.pin, self.v2c)
        r = self.sim.world.render(frame.cam_T_world, pinhole=self.pin)
        rgb = r.rgb if self.sim.sensor is None else self._through_sensor(r, frame)
        self.prev = frame
        name = f"{i:010d}"
        cv2.imwrite(str(self.tmp / kr.IMAGES / "data" / f"{name}.png"), cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))
        scan = scan_from_depth(r.depth_m, r.instance, self.pin, self.v2c, self.rows, self.cols)  # a rigid mount
        scan.tofile(self.tmp / kr.VELODYNE / "data" / f"{name}.bin")
        oxts = kr.oxts_line(rec.ego_speed_mps, rec.ego_yaw_rate_radps)
        (self.tmp / kr.OXTS / "data" / f"{name}.txt").write_text(oxts)
        self.times.append(rec.t_s)
        crit = rec.truth.critical
        depth = ttc = ""
        if crit is not None and crit.ahead:
            d = crit.gap_m + self.bumper_ahead_m
            depth = f"{d:.4f}"
            ttc = f"{d / crit.closing_speed_mps:.4f}" if crit.closing_speed_mps > 1e-9 and d > 0 else ""
        self.truth.append(f"{i},{rec.t_s:.6f},{rec.ego_speed_mps:.4f},{depth},{ttc}\n")

    def _through_sensor(self, r, frame) -> np.ndarray:
        """The native render's image through the run's sensor, moved by its exact flow since
        the previous capture (for the first, since the state one frame interval before)."""
        from sim.episode_sensor import frame_before
        from sim.sensor import apply_effects
        from sim.stepping import captures_ground_truth

        prev = self.prev if self.prev is not None else frame_before(self.sim, frame)
        gt = captures_ground_truth(self.pin, r.depth_m, r.instance, r.part, frame, prev)
        return apply_effects(r.rgb, self.sim.sensor, gt.flow_px, frame.t_s - prev.t_s, self.rng, self.codec)

    def finish(self) -> Path:
        """Timestamps, calibration and the truth file; the folder renamed into place."""
        if not self.times:
            raise kr.FootageError("KITTI export: the run captured no frame")
        lines = kr.timestamp_lines(self.times)
        for sub in (kr.IMAGES, kr.VELODYNE, kr.OXTS):
            (self.tmp / sub / "timestamps.txt").write_text(lines)
        fx, fy, cx, cy = self.pin.intrinsics()
        for name, text in kr.calib_texts(fx, fy, cx, cy, KITTI_HW[::-1], self.v2c).items():
            (self.tmp / name).write_text(text)
        header = "frame,t_s,ego_speed_mps,critical_depth_m,critical_ttc_s\n"
        (self.tmp / TRUTH_FILE).write_text(header + "".join(self.truth))
        if self.out.exists():
            self.out.rmdir()  # empty (checked at the start)
        self.tmp.rename(self.out)
        return self.out

    def abort(self) -> None:
        if self.tmp is not None:
            shutil.rmtree(self.tmp, ignore_errors=True)
