"""The KITTI raw layout: one drive's folder, read and written.

Files (a synced KITTI raw drive; ``oxts`` optional)::

    calib_cam_to_cam.txt     P_rect_02 (3x4, rectified camera 2), R_rect_00 (3x3)
    calib_velo_to_cam.txt    R (3x3), T (3) [m]: velodyne -> camera 0 (unrectified)
    image_02/data/NNNNNNNNNN.png, image_02/timestamps.txt
    velodyne_points/data/NNNNNNNNNN.bin, velodyne_points/timestamps.txt
    oxts/data/NNNNNNNNNN.txt  30 numbers per frame; index 8 is vf, the forward speed [m/s],
                              index 19 wz, the yaw rate [rad/s] (z up: + turning left)

Conventions (KITTI's): camera x right, y down, z forward; velodyne x forward, y left, z up;
a velodyne point X projects to the image as P_rect_02 R_rect_00 (R X + T). A velodyne file
holds float32 (x, y, z, reflectance) rows, 16 bytes each. Timestamps are
``YYYY-MM-DD HH:MM:SS.fffffffff`` lines; image frame i and velodyne frame i are the same
instant (synced data).
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime, timedelta
from pathlib import Path

import numpy as np

from sim.footage import FootageError, read_timestamps

CALIB_CAM = "calib_cam_to_cam.txt"
CALIB_VELO = "calib_velo_to_cam.txt"
IMAGES = "image_02"
VELODYNE = "velodyne_points"
OXTS = "oxts"
OXTS_FIELDS = 30  # numbers per oxts line
OXTS_VF = 8  # index of the forward speed [m/s]
OXTS_WZ = 19  # index of the angular rate about the up axis [rad/s], + turning left
EPOCH = datetime(2026, 1, 1)  # the date an export's timestamps count from


@dataclass(frozen=True)
class KittiDrive:
    """One drive, read and checked: calibration, the frames' files and capture times [s]."""

    folder: Path
    P_rect: np.ndarray  # (3, 4) rectified camera 2
    velo_to_cam: np.ndarray  # (4, 4): R_rect_00 [R | T], velodyne -> rectified camera
    image_paths: tuple[Path, ...]
    velo_paths: tuple[Path, ...]
    times_s: np.ndarray  # (N,) from the first frame
    ego_speed_mps: np.ndarray | None  # (N,) oxts vf, None without oxts

    @property
    def intrinsics(self) -> tuple[float, float, float, float]:
        """(fx, fy, cx, cy) [px] of image_02."""
        return float(self.P_rect[0, 0]), float(self.P_rect[1, 1]), float(self.P_rect[0, 2]), float(self.P_rect[1, 2])

    def scan(self, i: int) -> np.ndarray:
        """Velodyne frame ``i`` -> (N, 4) float32 x, y, z [m], reflectance."""
        return read_scan(self.velo_paths[i])


def _calib(path: Path, keys: dict[str, int]) -> dict[str, np.ndarray]:
    if not path.is_file():
        raise FootageError(f"calib {str(path)!r}: no such file")
    found: dict[str, np.ndarray] = {}
    for line in path.read_text().splitlines():
        name, _, values = line.partition(":")
        if name.strip() in keys:
            try:
                found[name.strip()] = np.array([float(x) for x in values.split()])
            except ValueError:
                raise FootageError(f"calib {str(path)!r}: {name.strip()} holds a value that is not a number") from None
    for key, n in keys.items():
        if key not in found:
            raise FootageError(f"calib {str(path)!r}: no {key} key")
        if found[key].size != n:
            raise FootageError(f"calib {str(path)!r}: {key} has {found[key].size} values, expected {n}")
    return found


def read_scan(path: Path) -> np.ndarray:
    size = path.stat().st_size
    if size % 16:
        raise FootageError(f"velodyne {str(path)!r}: {size} bytes, not a whole number of 16-byte (x, y, z, r) points")
    return np.fromfile(path, dtype=np.float32).reshape(-1, 4)


def _frames(folder: Path, sub: str, suffix: str) -> tuple[Path, ...]:
    d = folder / sub / "data"
    if not d.is_dir():
        raise FootageError(f"drive {str(folder)!r}: no {sub}/data folder")
    return _files(d, suffix)


def _files(data: Path, suffix: str) -> tuple[Path, ...]:
    """The frame files of a ``data`` folder, one a frame, in frame order (by name)."""
    return tuple(sorted(p for p in data.iterdir() if p.suffix == suffix))


def read_drive(folder: str | Path) -> KittiDrive:
    """A KITTI raw drive folder -> ``KittiDrive``; a missing file or key, a velodyne file of
    the wrong size, timestamps out of order or counts that disagree are refused by name."""
    folder = Path(folder)
    cam = _calib(folder / CALIB_CAM, {"P_rect_02": 12, "R_rect_00": 9})
    velo = _calib(folder / CALIB_VELO, {"R": 9, "T": 3})
    rect = np.eye(4)
    rect[:3, :3] = cam["R_rect_00"].reshape(3, 3)
    rt = np.eye(4)
    rt[:3, :3], rt[:3, 3] = velo["R"].reshape(3, 3), velo["T"]
    images, scans = _frames(folder, IMAGES, ".png"), _frames(folder, VELODYNE, ".bin")
    times = read_timestamps(folder / IMAGES / "timestamps.txt")
    if not (len(images) == len(scans) == len(times)):
        raise FootageError(
            f"drive {str(folder)!r}: {len(images)} images, {len(scans)} velodyne files and {len(times)} image "
            "timestamps; a synced drive has one of each per frame"
        )
    for p in scans:
        if p.stat().st_size % 16:
            read_scan(p)  # raises, naming the file
    speed = None
    if (folder / OXTS / "data").is_dir():
        speed = read_oxts(folder / OXTS, len(times))[0]
    return KittiDrive(folder, cam["P_rect_02"].reshape(3, 4), rect @ rt, images, scans, times, speed)


def read_oxts(folder: str | Path, frames: int) -> tuple[np.ndarray, np.ndarray]:
    """A KITTI ``oxts`` folder (its ``data/*.txt``, or that ``data`` folder itself) of a clip
    of ``frames`` frames -> (forward speed vf [m/s], yaw rate wz [rad/s], + left), each (N,).
    A count that differs from the frames', a line of the wrong length or a value that is not
    a number is refused, naming the file."""
    folder = Path(folder)
    data = folder / "data" if (folder / "data").is_dir() else folder
    if not data.is_dir():
        raise FootageError(f"oxts {str(folder)!r}: no such folder (a KITTI drive's oxts, holding data/*.txt)")
    files = _files(data, ".txt")
    if len(files) != frames:
        raise FootageError(f"oxts {str(folder)!r}: {len(files)} oxts files for {frames} frames")
    rows = np.array([_oxts_values(p) for p in files]).reshape(len(files), OXTS_FIELDS)
    return rows[:, OXTS_VF], rows[:, OXTS_WZ]


def _oxts_values(path: Path) -> list[float]:
    try:
        values = [float(x) for x in path.read_text().split()]
    except ValueError:
        raise FootageError(f"oxts {str(path)!r}: holds a value that is not a number") from None
    if len(values) != OXTS_FIELDS:
        raise FootageError(f"oxts {str(path)!r}: {len(values)} numbers, expected {OXTS_FIELDS}")
    if not np.isfinite(values).all():
        raise FootageError(f"oxts {str(path)!r}: holds a value that is not finite")
    return values


def timestamp_lines(times_s) -> str:
    return "".join(f"{(EPOCH + timedelta(seconds=float(t))).strftime('%Y-%m-%d %H:%M:%S.%f')}000\n" for t in times_s)


def calib_texts(fx: float, fy: float, cx: float, cy: float, size_wh, velo_to_cam: np.ndarray) -> dict[str, str]:
    """The two calib files of a drive whose camera 0 is camera 2 (no baseline, R_rect_00 = I)."""
    p = f"{fx:.6e} 0 {cx:.6e} 0 0 {fy:.6e} {cy:.6e} 0 0 0 1 0"
    k = f"{fx:.6e} 0 {cx:.6e} 0 {fy:.6e} {cy:.6e} 0 0 1"
    eye = "1 0 0 0 1 0 0 0 1"
    cam = (
        "calib_time: rendered by bittc-sim\n"
        f"S_02: {size_wh[0]} {size_wh[1]}\nK_02: {k}\nD_02: 0 0 0 0 0\nR_02: {eye}\nT_02: 0 0 0\n"
        f"S_rect_02: {size_wh[0]} {size_wh[1]}\nR_rect_00: {eye}\nR_rect_02: {eye}\nP_rect_00: {p}\nP_rect_02: {p}\n"
    )
    r = " ".join(f"{v:.9e}" for v in velo_to_cam[:3, :3].ravel())
    t = " ".join(f"{v:.9e}" for v in velo_to_cam[:3, 3])
    velo = f"calib_time: rendered by bittc-sim\nR: {r}\nT: {t}\ndelta_f: 0 0\ndelta_c: 0 0\n"
    return {CALIB_CAM: cam, CALIB_VELO: velo}


def oxts_line(forward_speed_mps: float, yaw_rate_radps: float = 0.0) -> str:
    values = np.zeros(OXTS_FIELDS)
    values[OXTS_VF], values[OXTS_WZ] = forward_speed_mps, yaw_rate_radps
    return " ".join(f"{v:g}" for v in values) + "\n"
