"""A real camera's calibration, and the two views the network sees of its frames.

Convention: pinhole intrinsics in the native frame's pixels, pixel centres at integer
(u, v) = (column, row). Resizing a frame by s = new / old maps a native pixel centre u to
(u + 0.5) s - 0.5, so fx scales by s and cx by that map.

* **Wide view**: the whole native frame resized to the network's size (H x W); its
  calibration is the native one scaled per axis (``resized``).
* **Fovea** (``fovea_crop``): a crop of the native frame resized to H x W_f, where W_f is
  the fovea width of the simulator's camera of that size. The crop is chosen so that a
  fovea pixel spans the angle it spans in training: the simulator's fovea has focal
  ZOOM x fy_wide, with fy_wide that of the default 30 deg vertical field of view at H
  rows, so the crop is (H, W_f) x f_native / (ZOOM fy_wide) native pixels. It is centred
  on the horizon point straight ahead (u = cx, v = cy - fy tan(pitch)), as in training,
  and shifted to lie inside the frame. A frame too small to hold the crop, or a crop with
  fewer native pixels than the fovea (it would be upsampled), is refused.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from sim.footage import FootageError

KITTI_CAMERA = "02"  # the left colour camera: image_02, P_rect_02


@dataclass(frozen=True)
class Intrinsics:
    """[px] of one image size: focal lengths and principal point."""

    fx_px: float
    fy_px: float
    cx_px: float
    cy_px: float

    def __post_init__(self) -> None:
        for name in ("fx_px", "fy_px"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise FootageError(f"{name} {v!r}: must be > 0")
        for name in ("cx_px", "cy_px"):
            if not math.isfinite(getattr(self, name)):
                raise FootageError(f"{name} {getattr(self, name)!r}: must be finite")

    def resized(self, from_hw: tuple[int, int], to_hw: tuple[int, int], origin_uv=(0, 0)) -> Intrinsics:
        """The intrinsics of the window starting at ``origin_uv`` [px] of size ``from_hw``
        resized to ``to_hw``."""
        sy, sx = to_hw[0] / from_hw[0], to_hw[1] / from_hw[1]
        return Intrinsics(
            self.fx_px * sx,
            self.fy_px * sy,
            (self.cx_px - origin_uv[0] + 0.5) * sx - 0.5,
            (self.cy_px - origin_uv[1] + 0.5) * sy - 0.5,
        )


def view_intrinsics(intr: Intrinsics, box, size_hw: tuple[int, int]) -> Intrinsics:
    """The intrinsics of a view: the crop ``box`` (u0, v0, u1, v1) [native px] of a frame
    with ``intr``, resized to ``size_hw`` (the whole frame's box: the wide view)."""
    u0, v0, u1, v1 = box
    return intr.resized((v1 - v0, u1 - u0), size_hw, (u0, v0))


def read_kitti_calib(path: str | Path, camera: str = KITTI_CAMERA) -> Intrinsics:
    """A KITTI raw ``calib_cam_to_cam.txt`` -> the rectified intrinsics of ``camera``
    (``P_rect_<camera>``: fx 0 cx tx / 0 fy cy ty / 0 0 1 0)."""
    p = Path(path)
    if not p.is_file():
        raise FootageError(f"calib {str(p)!r}: no such file")
    key = f"P_rect_{camera}"
    for line in p.read_text().splitlines():
        name, _, values = line.partition(":")
        if name.strip() == key:
            try:
                v = [float(x) for x in values.split()]
            except ValueError:
                raise FootageError(f"calib {str(p)!r}: {key} holds a value that is not a number") from None
            if len(v) != 12:
                raise FootageError(f"calib {str(p)!r}: {key} has {len(v)} values, expected 12 (a 3x4 matrix)")
            return Intrinsics(v[0], v[5], v[2], v[6])
    raise FootageError(f"calib {str(p)!r}: no {key} key (the rectified projection of camera {camera})")


def centred_box(center_uv, crop_wh: tuple[int, int], shape_hw: tuple[int, int]) -> tuple[int, int, int, int]:
    """(u0, v0, u1, v1) [native px, u1 and v1 exclusive] of a crop of ``crop_wh`` pixels
    centred on ``center_uv`` [px], shifted to lie inside a frame of ``shape_hw``."""
    (u, v), (cw, ch), (H, W) = center_uv, crop_wh, shape_hw
    u0 = min(max(int(round(u + 0.5 - cw / 2)), 0), W - cw)
    v0 = min(max(int(round(v + 0.5 - ch / 2)), 0), H - ch)
    return u0, v0, u0 + cw, v0 + ch


def training_fovea_focal_px(size_hw: tuple[int, int], zoom: float) -> tuple[float, int]:
    """-> (the simulator fovea's focal length [px] and width [px]) beside a wide view of ``size_hw``."""
    from sim.camera import CameraConfig

    fovea = CameraConfig(height_px=size_hw[0], width_px=size_hw[1], fovea_zoom=zoom).fovea()
    return float(fovea.fy_px), int(fovea.width_px)


def fovea_crop(
    shape_hw: tuple[int, int], intr: Intrinsics, zoom: float, size_hw: tuple[int, int], pitch_deg: float
) -> tuple[tuple[int, int, int, int], tuple[int, int]]:
    """-> ((u0, v0, u1, v1) [native px, u1 and v1 exclusive] of the fovea's crop, the fovea's
    (H, W_f) [px]) for a network size ``size_hw`` (see the module docstring)."""
    H, W = shape_hw
    f_train, w_f = training_fovea_focal_px(size_hw, zoom)
    h_f = size_hw[0]
    scale = math.sqrt(intr.fx_px * intr.fy_px) / f_train  # native px per fovea px
    cw, ch = int(round(w_f * scale)), int(round(h_f * scale))
    if cw > W or ch > H:
        raise FootageError(
            f"fovea zoom {zoom:g}: a fovea pixel spans the training angle at {cw}x{ch} native px, larger than the "
            f"{W}x{H} px frame (fx {intr.fx_px:g} px); a smaller zoom fits"
        )
    if cw < w_f or ch < h_f:
        raise FootageError(
            f"fovea zoom {zoom:g}: its crop is {cw}x{ch} native px, fewer than the fovea's {w_f}x{h_f} (fx "
            f"{intr.fx_px:g} px is too short for this zoom: it would be upsampled); a smaller zoom fits"
        )
    u = intr.cx_px
    v = intr.cy_px - intr.fy_px * math.tan(math.radians(pitch_deg))
    return centred_box((u, v), (cw, ch), shape_hw), (h_f, w_f)
