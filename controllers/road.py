"""What the calibration tells about the road ahead, per image row and column.

Convention: flat road, camera pitched down by ``pitch`` p about its x axis (no roll),
OpenCV camera frame (x right, y down, z forward), pixel rows v with the principal
point at row cy. A pixel's ray r = ((u - cx)/fx, (v - cy)/fy, 1) meets the ground,
whose downward normal in the camera frame is n = (0, cos p, sin p), at depth

    Z(v) = h / (cos p * (v - cy)/fy + sin p)        (rows below the horizon; else +inf)

with h the camera's height. Driving straight at speed s, a static point's depth falls
at s * cos p, so its camera-plane TTC (the estimator's tau, from the latest frame) is

    tau_ground(v) = Z(v) / (s * cos p)              (+inf at standstill or above the horizon)

A vertical face standing on the road at depth Z has that TTC over all its rows when
static; the ground beside it lies further (larger tau) on every row above its base.
So a pixel inside a geofence tau_i counts as an obstacle only on rows whose ground
lies clearly outside the fence. A static point at camera-plane TTC tau_i lies at
depth Z_i = s * cos p * tau_i; the ego's corridor (its width plus a margin, straight
ahead) spans |u - cx| <= fx * half_width / Z_i columns at that depth.
"""

from __future__ import annotations

import math

import numpy as np

from controllers.base import Calibration


def ground_depth_per_row(cal: Calibration) -> np.ndarray:
    """(H,) float64 depth Z [m] of the ground seen at each row's centre; +inf above the horizon."""
    p = math.radians(cal.pitch_deg)
    v = np.arange(cal.height_px, dtype=np.float64)
    denom = math.cos(p) * (v - cal.cy_px) / cal.fy_px + math.sin(p)
    with np.errstate(divide="ignore"):
        z = np.where(denom > 1e-9, cal.mount_height_m / np.maximum(denom, 1e-12), np.inf)
    return z


def ground_ttc_per_row(cal: Calibration, ego_speed_mps: float) -> np.ndarray:
    """(H,) float64 camera-plane TTC [s] of the static ground at each row; +inf where the
    ground does not approach (standstill, above the horizon)."""
    closing = ego_speed_mps * math.cos(math.radians(cal.pitch_deg))
    if closing <= 1e-6:
        return np.full(cal.height_px, np.inf)
    return ground_depth_per_row(cal) / closing


def static_depth_m(cal: Calibration, ego_speed_mps: float, tau_s: float) -> float:
    """Depth Z [m] of a static point whose camera-plane TTC is ``tau_s``."""
    return ego_speed_mps * math.cos(math.radians(cal.pitch_deg)) * tau_s


def corridor_columns(
    cal: Calibration, half_width_m: float, depth_m: float, centre_px: float | None = None
) -> tuple[int, int]:
    """Inclusive column range [u0, u1] of the ego's corridor at ``depth_m`` (clipped to the
    image), centred on column ``centre_px`` (default the principal point: straight ahead)."""
    centre = cal.cx_px if centre_px is None else centre_px
    half_px = cal.fx_px * half_width_m / max(depth_m, 1e-6)
    u0 = max(0, int(math.ceil(centre - half_px)))
    u1 = min(cal.width_px - 1, int(math.floor(centre + half_px)))
    return u0, u1
