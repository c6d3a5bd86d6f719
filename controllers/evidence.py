"""Evidence in one view's geofence maps: which fenced pixels stand on the road in the ego's
corridor (the rules 2-4 of ``controllers.geofence``), and the fenced regions across the
whole width that the tracker (``controllers.tracker``) follows.

Convention: OpenCV camera frame (x right, y down, z forward), flat road, the camera pitched
down by p. Turning at yaw rate w [rad/s] (+ left) at speed s, a static point at (X, Z)
moves by dX/dt = w Z, dZ/dt = -(s cos p + w X); its camera-plane TTC is
Z / (s cos p + w X), and the ego's path bends to X_path(Z) = -k Z^2 / 2 with the
curvature k = w / s. At w = 0 both are the straight-road rules of ``controllers.road``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import cv2
import numpy as np

from controllers.base import Calibration
from controllers.road import corridor_columns, ground_depth_per_row, ground_ttc_per_row, static_depth_m


def standing_regions(
    mask: np.ndarray, lowest_row: int, contact_px: int, min_rows: float = 0.0
) -> tuple[int, np.ndarray]:
    """8-connected regions of a (H, W) bool mask whose bottom row is at least
    ``lowest_row - contact_px`` and that span at least ``min_rows`` rows -> (pixels of the
    largest, (H, W) bool mask of them all). The height keeps out the fence's own edge on
    the road: where the road's fence runs a little beyond the nominal boundary of the
    counted rows, it leaves a strip a few rows tall along the lowest counted row,
    standing there like an obstacle of no height."""
    if not mask.any():
        return 0, np.zeros_like(mask)
    n, labels, stats, _ = cv2.connectedComponentsWithStats(mask.astype(np.uint8), connectivity=8)
    bottom = stats[1:, cv2.CC_STAT_TOP] + stats[1:, cv2.CC_STAT_HEIGHT] - 1
    tall = stats[1:, cv2.CC_STAT_HEIGHT] >= min_rows
    keep = np.flatnonzero((bottom >= lowest_row - contact_px) & tall) + 1
    if keep.size == 0:
        return 0, np.zeros_like(mask)
    return int(stats[keep, cv2.CC_STAT_AREA].max()), np.isin(labels, keep)


def bottom_row(mask: np.ndarray) -> int:
    """The lowest row (largest index) of a (H, W) bool mask with at least one pixel set:
    a fence's lowest counted row, a region's bottom."""
    return int(np.flatnonzero(mask.any(axis=1)).max())


def need_px(cal: Calibration, depth_m: float, min_region_px: float, min_face_m2: float) -> float:
    """[px] the smallest standing region that counts at a fence's static depth ``depth_m``:
    at least ``min_region_px``, and the area a face of ``min_face_m2`` covers there."""
    return max(min_region_px, cal.fx_px * cal.fy_px * min_face_m2 / depth_m**2 if depth_m > 1e-6 else 0.0)


def ground_ttc_map(cal: Calibration, speed_mps: float, yaw_rate_radps: float = 0.0) -> np.ndarray:
    """(H, W) camera-plane TTC [s] of the static ground seen at each pixel (+inf where it
    does not approach: above the horizon, at standstill)."""
    if yaw_rate_radps == 0.0:  # straight on: every column of a row alike (controllers.road)
        return np.repeat(ground_ttc_per_row(cal, speed_mps)[:, None], cal.width_px, axis=1)
    z = ground_depth_per_row(cal)[:, None]
    x_over_z = (np.arange(cal.width_px, dtype=np.float64) - cal.cx_px) / cal.fx_px
    rate = (
        speed_mps * math.cos(math.radians(cal.pitch_deg)) + yaw_rate_radps * np.where(np.isfinite(z), z, 0.0) * x_over_z
    )
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where((rate > 1e-6) & np.isfinite(z), z / np.maximum(rate, 1e-12), np.inf)


def counted_pixels(tau_ground: np.ndarray, tau_s: float, ground_margin: float) -> np.ndarray:
    """(H, W) bool: pixels where fence ``tau_s`` can be judged: the ground there and one row
    below lies clearly outside the fence (TTC > ``ground_margin`` x tau)."""
    below = np.vstack([tau_ground[1:], tau_ground[-1:]])  # the ground one row lower
    return (tau_ground > ground_margin * tau_s) & (below > ground_margin * tau_s)


def fenced_road_edge(inside: np.ndarray, min_share: float = 0.1) -> int | None:
    """Row where a fence's run of inside pixels up from the image's bottom row ends (the
    run's highest row), the median over the columns that have such a run: where the
    estimator puts the road's own fence edge. None when under ``min_share`` of the columns
    have one (the near road lies outside the fence, or below the view). An obstacle moves
    the edge only in its own columns, which the median outvotes unless it holds most of the
    columns that have a run (then ``judged_pixels``' cap keeps its upper part)."""
    h = inside.shape[0]
    outside_up = ~inside[::-1]  # from the bottom row up
    run = np.where(outside_up.any(axis=0), outside_up.argmax(axis=0), h)
    have = run > 0
    if have.sum() < max(min_share * inside.shape[1], 1):
        return None
    return int(np.median(h - run[have]))


def judged_pixels(tau_ground: np.ndarray, fence: np.ndarray, tau_s: float, cfg) -> np.ndarray:
    """(H, W) bool: rule 2 of ``controllers.geofence`` for fence ``tau_s``, its (H, W) map
    ``fence`` (inside above ``cfg.prob_inside``) and the ground's TTC map ``tau_ground``:
    the pixels whose ground lies outside the fence by ``cfg.ground_margin``
    (``counted_pixels``), and, with ``cfg.road_edge_rows`` = N >= 0, more than N rows
    above the road's fence edge as the estimator draws it (``fenced_road_edge``; no bound
    where it finds none): an estimator that reads the road as closing faster than it does
    fences it past the boundary, and bumps along that edge would stand in the counted rows
    like obstacles. With the bound on, rows whose ground lies outside the fence by
    ``cfg.road_edge_cap`` always count. The map is thresholded only with the bound on."""
    band = counted_pixels(tau_ground, tau_s, cfg.ground_margin)
    edge = fenced_road_edge(fence > cfg.prob_inside) if cfg.road_edge_rows >= 0 else None
    if edge is None:
        return band
    rows = np.arange(band.shape[0])[:, None]
    return band & ((rows < edge - cfg.road_edge_rows) | counted_pixels(tau_ground, tau_s, cfg.road_edge_cap))


def judged_bands(cal: Calibration, maps: np.ndarray, thr: np.ndarray, speed_mps: float, yaw_rate_radps: float, cfg):
    """(H, W) bool per fence of ``thr`` (its map in ``maps``): the pixels where it can be
    judged (``judged_pixels``) on the ground seen at this speed and yaw rate."""
    tau_ground = ground_ttc_map(cal, speed_mps, yaw_rate_radps)
    return [judged_pixels(tau_ground, m, tau, cfg) for m, tau in zip(maps, thr)]


def corridor_mask(cal: Calibration, counted: np.ndarray, half_w_m: float, depth_m: float, curvature: float):
    """(H, W) bool: the counted pixels in the columns of the ego's corridor at ``depth_m``
    (its width plus margins, bent along the path of curvature ``curvature`` [1/m]:
    centred on X_path / Z = -k Z / 2)."""
    out = np.zeros_like(counted)
    u0, u1 = corridor_columns(cal, half_w_m, depth_m, cal.cx_px - cal.fx_px * curvature * depth_m / 2)
    if u1 >= u0:
        out[:, u0 : u1 + 1] = counted[:, u0 : u1 + 1]
    return out


@dataclass(frozen=True)
class Blob:
    """A fenced region standing on the road, anywhere across the view: its pixels, column
    extent [px], the smallest fence threshold [s] that holds most of it, the depth [m]
    of the ground where it stands when that shows (None where the fenced road runs on
    below it), and the column [px] of its inner edge (nearest the image centre; None: the
    end of its extent on that side)."""

    mask: np.ndarray
    u_left: float
    u_right: float
    tau_bound_s: float
    contact_depth_m: float | None = None
    inner_px: float | None = None


def contact_depth(
    fenced: np.ndarray, mask: np.ndarray, u0: int, u1: int, ground_depth: np.ndarray, pad_px: int = 0
) -> float | None:
    """Depth [m] of the ground under a region: below its bottom, the first row of its columns
    [u0, u1], widened by ``pad_px`` each side, that the fence leaves free is where it stands;
    None when the fence reaches the image's bottom there (the road under it is inside the
    fence too: a target closing no faster than the ego drives). The widening keeps a
    walker's swinging leg, which reaches past the columns of its upper body, from leaving
    the row beside it free."""
    bottom = bottom_row(mask)
    rows = fenced[bottom:, max(u0 - pad_px, 0) : u1 + pad_px + 1].any(axis=1)
    free = np.flatnonzero(~rows)
    if free.size == 0:
        return None
    z = float(ground_depth[bottom + int(free[0])])
    return z if math.isfinite(z) else None


def inner_edge_slant(mask: np.ndarray, left_of_centre: bool) -> float:
    """[px per row] how fast a region's inner edge (its column nearest the image centre in
    each row) moves outwards, away from the centre, row by row downwards (least squares;
    0 for a region one row tall). An upright object's edge is vertical (about 0); a strip of
    ground along the road at lateral offset X, seen from height h, slants outwards at
    X / h px per row (square pixels): its nearer rows lie further out."""
    rows = np.flatnonzero(mask.any(axis=1))
    if rows.size < 2:
        return 0.0
    cols = [np.flatnonzero(mask[r]) for r in rows]
    inner = np.array([c.max() if left_of_centre else c.min() for c in cols], dtype=np.float64)
    slope = float(np.polyfit(rows.astype(np.float64), inner, 1)[0])
    return -slope if left_of_centre else slope


def fenced_blobs(
    inside: np.ndarray,
    touch: np.ndarray,
    maps: np.ndarray,
    thr: np.ndarray,
    prob_inside: float,
    need_px: float,
    ground_depth: np.ndarray,
    join_rows: int = 0,
    pad_px: np.ndarray | None = None,
    need_far_px: Callable[[float], float] | None = None,
) -> list[Blob]:
    """Regions of ``inside`` (counted inside pixels, (H, W) bool) that stand on the road,
    i.e. hold a pixel of ``touch`` (the rows where a standing region's bottom lies), of at
    least ``need_px`` pixels, each with the smallest fence of ``thr`` that holds half of it
    and the depth where it stands (``contact_depth`` in that fence; ``ground_depth``: (H,)
    per row [m]). Parts one above the other with at most ``join_rows`` rows between them
    are one region: a road user's upper body counted in a larger fence and its legs in a
    smaller one, with the rows between counted in neither. ``pad_px`` (K,): per fence, how
    far beside a region its ground is read (``contact_depth``). ``need_far_px`` (ground
    depth [m] -> [px]): a region whose ground depth is known needs only that many pixels
    where they are fewer than ``need_px`` (a region judged at the depth where it stands)."""
    if not inside.any():
        return []
    mask = inside.astype(np.uint8)
    if join_rows > 0:  # each part reaches join_rows rows up; only columns it already holds
        mask = cv2.dilate(mask, np.ones((join_rows + 1, 1), np.uint8), anchor=(0, 0))
    n, labels, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
    if join_rows > 0:  # the regions are the inside pixels of each group, their area theirs
        labels = np.where(inside, labels, 0)
        stats[:, cv2.CC_STAT_AREA] = np.bincount(labels.ravel(), minlength=n)
    standing = np.zeros(n, dtype=bool)
    standing[labels[touch & inside]] = True
    out = []
    floor_px = need_px if need_far_px is None else min(need_px, need_far_px(math.inf))
    for k in range(1, n):
        if not standing[k] or stats[k, cv2.CC_STAT_AREA] < floor_px:
            continue
        m = labels == k
        shares = [(maps[i][m] > prob_inside).mean() for i in range(len(thr))]
        i_min = next((i for i, sh in enumerate(shares) if sh >= 0.5), len(thr) - 1)
        u0 = int(stats[k, cv2.CC_STAT_LEFT])
        u1 = u0 + int(stats[k, cv2.CC_STAT_WIDTH]) - 1
        # the smallest fence that holds it: the road between it and the ego shows there first
        pad = int(pad_px[i_min]) if pad_px is not None else 0
        z = contact_depth(maps[i_min] > prob_inside, m, u0, u1, ground_depth, pad)
        need_k = need_px if need_far_px is None or z is None else min(need_px, need_far_px(z))
        if stats[k, cv2.CC_STAT_AREA] < need_k:
            continue
        out.append(Blob(m, float(u0), float(u1), float(thr[i_min]), z))
    return out


def _predicted_regions(mask, cal: Calibration, cfg, speed_mps: float, largest_s: float, min_height_m: float):
    """(pixels of the largest, (H, W) bool mask of them all) of the regions of ``mask``
    (predicted into the path) that span ``min_height_m`` at the static depth of the largest
    fence ``largest_s`` [s], when the largest of them covers the area of a face there,
    wherever they stand: a car that the tracker predicts across a turning ego's path may
    float above the counted rows (its road shows beneath it); no region: (0, empty)."""
    depth = static_depth_m(cal, speed_mps, largest_s)
    rows = cal.fy_px * min_height_m / depth if depth > 1e-6 else 0.0
    area, found = standing_regions(mask, 0, 0, rows)
    if area < need_px(cal, depth, cfg.min_region_px, cfg.min_face_m2):
        return 0, np.zeros_like(mask)
    return area, found


def in_path_evidence(
    maps: np.ndarray,
    thr: np.ndarray,
    bands: list[np.ndarray],
    cal: Calibration,
    cfg,
    speed_mps: float,
    yaw_rate_radps: float,
    predicted: np.ndarray,
    min_height_m: float = 0.0,
    static: bool = True,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rules 2-4 of ``controllers.geofence`` in one view: sorted (K, H, W) maps of fences
    ``thr`` [s], their counted pixels ``bands``, the tracker's ``predicted`` (H, W) regions
    and the ``controllers.geofence_config.GeofenceConfig`` ``cfg`` -> (in-path region size
    per fence [px], counted mask, corridor mask). A region counts in the corridor at the
    fence's static depth (not without ``static``) or where the tracker predicts it into
    the path, standing on the road, ``min_height_m`` tall there and big enough (with
    ``cfg.tracker.turn_across``, wherever it stands, if as tall and as big as the largest
    fence asks: ``_predicted_regions``)."""
    c = cfg
    curvature = yaw_rate_radps / speed_mps if speed_mps > c.min_speed_mps else 0.0
    half_w = cal.ego_width_m / 2 + c.corridor_margin_m
    counted = np.zeros(maps.shape[1:], dtype=bool)
    corridor = np.zeros(maps.shape[1:], dtype=bool)
    sizes = np.zeros(len(thr), dtype=np.int64)
    for i, tau in enumerate(thr):
        if not bands[i].any():
            continue
        depth = static_depth_m(cal, speed_mps, tau)
        region = corridor_mask(cal, bands[i], half_w, depth, curvature)
        lowest = bottom_row(bands[i])
        inside = maps[i] > c.prob_inside
        rows = cal.fy_px * min_height_m / depth if depth > 1e-6 else 0.0
        area, standing = standing_regions(inside & region & static, lowest, c.contact_px, rows)
        need = need_px(cal, depth, c.min_region_px, c.min_face_m2)
        ok = area >= need
        if c.tracker.turn_across:  # the largest fence's size suffices for a predicted region
            area_p, ahead = _predicted_regions(predicted & inside & bands[i], cal, c, speed_mps, thr[-1], min_height_m)
            ok_p, rank_p = area_p > 0, max(area_p, need) if area_p else 0
        else:
            area_p, ahead = standing_regions(predicted & inside & bands[i], lowest, c.contact_px, rows)
            ok_p, rank_p = area_p >= need, area_p
        if rank_p > area:
            area, standing, ok = area_p, ahead, ok_p
        if ok:
            sizes[i] = area
            counted |= standing
        corridor |= region
    return sizes, counted, corridor
