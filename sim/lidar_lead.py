"""The in-path lead from lidar, and its TTC from the fitted depth over time.

Per velodyne scan (velodyne frame: x forward, y left, z up, ``sim.kitti_raw``):

1. **Ground**: the ``GROUND_PERCENTILE`` percentile of the heights of the points within
   ``GROUND_HALF_WIDTH_M`` to the side, ``GROUND_RANGE_M`` ahead (the road around the
   lead, which can fill the corridor when close).
2. **Obstacles in the corridor**: points with |y| <= the corridor's half width (the ego's
   half width plus a margin), between ``MIN_HEIGHT_M`` and ``MAX_HEIGHT_M`` above that
   ground, at least ``MIN_AHEAD_M`` ahead.
3. **The lead's face**: the nearest such point with at least ``MIN_FACE_POINTS`` obstacle
   points within ``FACE_DEPTH_M`` behind it (a lone return is noise); the face is those
   points. Its depth is the ``FACE_PERCENTILE`` percentile of their distance ahead (x)
   less the camera's (the velodyne sits behind KITTI's camera) [m]: the nearest part of
   the face, along the road, from the camera (its pitch tilts the camera's Z by a few
   centimetres over the face's height).

TTC per frame (``fit_ttc``): a polynomial through the face's depth over the frames within
``FIT_WINDOW_S`` / 2 of it (a parabola from 5 frames on, so a constant deceleration fits
exactly; a line below), cut where the depth stops changing: a step under ``STALL_M`` or
under ``STALL_SHARE`` of the steps beside the frame itself (contact, or both at rest), so
that a sudden stop does not bend the fit before it. TTC = depth(t) /
closing speed, camera plane, from that frame's capture; +inf when the depth does not
shrink, NaN without a lead or a fit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

GROUND_RANGE_M = (3.0, 30.0)
GROUND_HALF_WIDTH_M = 5.0
GROUND_PERCENTILE = 5.0
CORRIDOR_MARGIN_M = 0.3  # [m] beyond the ego's half width, each side
MIN_HEIGHT_M = 0.3  # [m] above the ground
MAX_HEIGHT_M = 3.0
MIN_AHEAD_M = 1.0
FACE_DEPTH_M = 0.5
FACE_PERCENTILE = 10.0  # [%] of the face points' distances: its nearest part, not a sloping one behind
MIN_FACE_POINTS = 5
FIT_WINDOW_S = 1.0
MIN_FIT_POINTS = 3
STALL_M = 0.005  # [m] a depth change per frame below this is no motion
STALL_SHARE = 0.3  # [-] nor is one below this share of the steps beside the frame fitted


@dataclass(frozen=True)
class LeadObservation:
    depth_m: (
        float  # level distance of the face ahead of the camera [m] (its points' FACE_PERCENTILE x), NaN without a lead
    )
    face_cam: np.ndarray  # (N, 3) the face's points in the rectified camera frame [m]
    road_cam: np.ndarray  # (M, 3) corridor road points nearer than the lead, camera frame [m]


def _to_cam(points: np.ndarray, velo_to_cam: np.ndarray) -> np.ndarray:
    return points[:, :3] @ velo_to_cam[:3, :3].T + velo_to_cam[:3, 3]


def find_lead(scan: np.ndarray, velo_to_cam: np.ndarray, half_width_m: float) -> LeadObservation:
    """(N, 4) velodyne points -> the lead in the corridor of half width ``half_width_m``."""
    x, y, z = scan[:, 0], scan[:, 1], scan[:, 2]
    corridor = (np.abs(y) <= half_width_m) & (x >= MIN_AHEAD_M)
    near = (np.abs(y) <= GROUND_HALF_WIDTH_M) & (x >= GROUND_RANGE_M[0]) & (x <= GROUND_RANGE_M[1])
    ground = float(np.percentile(z[near], GROUND_PERCENTILE)) if near.any() else float(np.min(z, initial=0.0))
    obstacle = corridor & (z >= ground + MIN_HEIGHT_M) & (z <= ground + MAX_HEIGHT_M)
    empty = np.zeros((0, 3))
    xs = np.sort(x[obstacle])
    # the nearest obstacle point with MIN_FACE_POINTS within FACE_DEPTH_M behind it
    ahead = np.searchsorted(xs, xs + FACE_DEPTH_M, side="right") - np.arange(len(xs))
    solid = np.flatnonzero(ahead >= MIN_FACE_POINTS)
    lead_x = float(xs[solid[0]]) if len(solid) else None
    road = corridor & (z < ground + 0.15)
    if lead_x is None:
        return LeadObservation(float("nan"), empty, _to_cam(scan[road], velo_to_cam))
    face = obstacle & (x >= lead_x) & (x <= lead_x + FACE_DEPTH_M)
    face_cam = _to_cam(scan[face], velo_to_cam)
    road_cam = _to_cam(scan[road & (x < lead_x - 1.0)], velo_to_cam)
    camera_x = float(np.linalg.inv(velo_to_cam)[0, 3])  # the camera's centre along x (KITTI: 0.27 m ahead)
    return LeadObservation(float(np.percentile(scan[face, 0], FACE_PERCENTILE)) - camera_x, face_cam, road_cam)


def fit_ttc(times_s: np.ndarray, depth_m: np.ndarray, window_s: float = FIT_WINDOW_S) -> np.ndarray:
    """(N,) times [s] and lead depths [m] (NaN: none) -> (N,) camera-plane TTC [s]."""
    t, d = np.asarray(times_s, float), np.asarray(depth_m, float)
    step = np.abs(np.diff(d))  # NaN where either frame has no lead
    out = np.full(len(t), np.nan)
    for i in range(len(t)):
        if not np.isfinite(d[i]):
            continue
        beside = step[max(i - 1, 0) : i + 1]
        ref = float(np.nanmedian(beside)) if np.isfinite(beside).any() else 0.0
        moving = step >= max(STALL_M, STALL_SHARE * ref)  # False where NaN
        lo = hi = i
        while lo > 0 and moving[lo - 1] and t[i] - t[lo - 1] <= window_s / 2 + 1e-9:
            lo -= 1
        while hi < len(t) - 1 and moving[hi] and t[hi + 1] - t[i] <= window_s / 2 + 1e-9:
            hi += 1
        n = hi - lo + 1
        if n < MIN_FIT_POINTS:
            out[i] = np.inf if n == 1 or not moving[min(i, len(moving) - 1)] else np.nan
            continue
        coef = np.polyfit(t[lo : hi + 1] - t[i], d[lo : hi + 1], 2 if n >= 5 else 1)
        slope, icpt = coef[-2], coef[-1]
        out[i] = icpt / -slope if slope < 0 else np.inf
    return out
