"""Fence decisions on a KITTI raw drive, scored against the lead's lidar TTC.

Truth (``sim.lidar_lead``): the in-path lead's face from each scan, its camera-plane depth
fitted over time, its TTC per frame.

Time compression: a pair of frames k apart (k in ``strides``) is shown to the estimator as
if it were its trained ``frame_dt_s`` apart. Motion in depth over the pair is that of a
k-times-faster approach, so the TTC the pair asks about is the effective
tau_eff = tau x frame_dt_s / (t_i - t_{i-k}) (tau / k on 10 Hz footage). Slow real
approaches thus cover the short TTCs that braking needs, with real pixels.

Per pair, in the wide view (the native frame resized to ``size_hw``) and the fovea (the
crop at the training angle per pixel, ``sim.footage_camera``; ``fovea_zoom``):

* **The lead's region**: the bounding box of its face points projected into each view
  that holds it. The estimator's fence decision in a view: more than half the box's
  pixels inside (p > 0.5); the pair's decision: inside in either view, as the geofence
  controller decides. Truth: 0 < tau_eff <= threshold. Counted per threshold: correct, misses
  (inside in truth, outside in the decision), false alarms (the reverse).
* **Continuous**: the median of the estimator's TTC over the box (in the view where it
  covers more pixels) against tau_eff (the
  Spearman rank correlation and the median ratio, over pairs with tau_eff within the
  trained range).
* **The road**: the corridor's road points nearer than the lead, projected into the wide
  view; their truth is
  a static point's, tau = Z / v_ego (oxts), time-compressed as above. The false-fence
  share: of the road pixels outside a fence in truth, the share inside it in the decision
  (None without oxts).

Pairs are kept where the lead is seen in both frames and 0 < tau_eff <= ``max_tau_s``.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from sim.footage_camera import Intrinsics, fovea_crop, view_intrinsics
from sim.footage_views import crop_view
from sim.kitti_raw import KittiDrive
from sim.lidar_lead import CORRIDOR_MARGIN_M, find_lead, fit_ttc
from sim.vehicles import EGO_SIZE_M


@dataclass(frozen=True)
class KittiEvalSettings:
    thresholds_s: tuple[float, ...] = (0.9, 1.6, 2.4)  # [s] in the estimator's time base
    strides: tuple[int, ...] = tuple(range(1, 17))  # [frames] pair spacings
    size_hw: tuple[int, int] = (96, 288)  # [px] the network's view
    max_tau_s: float = 8.0  # [s] pairs with a larger effective TTC are not scored
    fovea_zoom: float | None = 4.0  # the fovea beside the wide view (None: the wide view alone)


def lidar_truth(drive: KittiDrive) -> tuple[list, np.ndarray]:
    """-> (each frame's ``LeadObservation``, (N,) the lead's camera-plane TTC [s])."""
    half = EGO_SIZE_M[1] / 2 + CORRIDOR_MARGIN_M
    leads = [find_lead(drive.scan(i), drive.velo_to_cam, half) for i in range(len(drive.times_s))]
    return leads, fit_ttc(drive.times_s, np.array([lead.depth_m for lead in leads]))


@dataclass(frozen=True)
class _View:
    name: str
    box: tuple[int, int, int, int]  # (u0, v0, u1, v1) [native px] of the crop
    size_hw: tuple[int, int]  # [px]
    intr: Intrinsics  # of the resized view


def drive_views(drive: KittiDrive, s: KittiEvalSettings) -> list[_View]:
    """The wide view (the whole frame resized) and, with ``s.fovea_zoom``, the fovea cropped
    at the training angle per pixel around the horizon point ahead (``sim.footage_camera``;
    the pitch is the camera's against the level velodyne)."""
    h0, w0 = cv2.imread(str(drive.image_paths[0]), cv2.IMREAD_UNCHANGED).shape[:2]
    native = Intrinsics(*drive.intrinsics)
    views = [_View("wide", (0, 0, w0, h0), s.size_hw, view_intrinsics(native, (0, 0, w0, h0), s.size_hw))]
    if s.fovea_zoom is not None:
        forward = drive.velo_to_cam[:3, :3].T @ np.array([0.0, 0.0, 1.0])  # the optical axis, velodyne frame
        pitch_deg = float(np.degrees(-np.arcsin(np.clip(forward[2], -1, 1))))
        box, hw = fovea_crop((h0, w0), native, s.fovea_zoom, s.size_hw, pitch_deg)
        views.append(_View("fovea", box, hw, view_intrinsics(native, box, hw)))
    return views


def _project(points_cam: np.ndarray, drive: KittiDrive, intr: Intrinsics) -> np.ndarray:
    """(N, 3) rectified camera-0 points -> (N, 2) (u, v) in a view of camera 2 with ``intr``."""
    K = drive.P_rect[:3, :3]
    p = points_cam + np.linalg.solve(K, drive.P_rect[:3, 3])  # camera 2's centre (P = K [I | t])
    z = np.maximum(p[:, 2:3], 1e-6)
    return np.concatenate([intr.fx_px * p[:, :1] / z + intr.cx_px, intr.fy_px * p[:, 1:2] / z + intr.cy_px], 1)


def _box(uv: np.ndarray, size_hw) -> tuple[slice, slice] | None:
    if len(uv) == 0:
        return None
    u0, v0 = np.floor(uv.min(0)).astype(int)
    u1, v1 = np.ceil(uv.max(0)).astype(int) + 1
    u0, v0, u1, v1 = max(u0, 0), max(v0, 0), min(u1, size_hw[1]), min(v1, size_hw[0])
    return (slice(v0, v1), slice(u0, u1)) if u1 > u0 and v1 > v0 else None


def _read(drive: KittiDrive, i: int, views: list[_View]) -> dict[str, np.ndarray]:
    rgb = cv2.cvtColor(cv2.imread(str(drive.image_paths[i]), cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB)
    return {v.name: crop_view(rgb, v.box, v.size_hw) for v in views}


def pair_rows(drive: KittiDrive, estimator, s: KittiEvalSettings, truth, continuous: bool = True) -> list[dict]:
    """One row per scored pair (see the module docstring); ``truth``: ``lidar_truth(drive)``."""
    leads, tau = truth
    views = drive_views(drive, s)
    ests = {
        v.name: estimator if v.name == "wide" or not hasattr(estimator, "fork") else estimator.fork() for v in views
    }
    thr = np.asarray(s.thresholds_s, float)
    images: dict[int, dict] = {}
    rows = []
    for i in range(len(drive.times_s)):
        boxes = {v.name: _box(_project(leads[i].face_cam, drive, v.intr), v.size_hw) for v in views}
        boxes = {k: b for k, b in boxes.items() if b is not None}
        if not boxes or not np.isfinite(tau[i]):
            continue
        for k in s.strides:
            j = i - k
            if j < 0 or not np.isfinite(leads[j].depth_m):
                continue
            gap = float(drive.times_s[i] - drive.times_s[j])
            tau_eff = float(tau[i]) * estimator.dt_s / gap
            if not 0 < tau_eff <= s.max_tau_s:
                continue
            for f in (i, j):
                if f not in images:
                    images[f] = _read(drive, f, views)
            row = {"frame": i, "prev_frame": j, "stride": k, "pair_dt_s": round(gap, 6)}
            row |= {"tau_s": round(float(tau[i]), 4), "tau_eff_s": round(tau_eff, 4)}
            maps = {n: ests[n].geofence(images[j][n], images[i][n], thr) for n in boxes}
            for q, t in enumerate(thr):
                per_view = {n: int((maps[n][q][b] > 0.5).mean() > 0.5) for n, b in boxes.items()}
                row |= {f"inside_{n}_{t:g}s": d for n, d in per_view.items()}
                row[f"inside_{t:g}s"] = int(any(per_view.values()))  # either view, as the controller
                row[f"truth_{t:g}s"] = int(tau_eff <= t)
            if continuous:  # the view in which the lead covers more pixels
                n, b = max(
                    boxes.items(), key=lambda nb: (nb[1][0].stop - nb[1][0].start) * (nb[1][1].stop - nb[1][1].start)
                )
                row["tau_hat_s"] = round(float(np.median(ests[n].continuous(images[j][n], images[i][n])[b])), 4)
            if "wide" in maps and drive.ego_speed_mps is not None and drive.ego_speed_mps[i] > 0.1:
                _road_columns(row, leads[i].road_cam, maps["wide"], thr, drive, views[0], estimator.dt_s / gap, i)
            rows.append(row)
        images = {f: im for f, im in images.items() if f > i - max(s.strides) - 1}
    return rows


def _road_columns(row, road_cam, maps, thr, drive, view: _View, compress, i) -> None:
    uv = np.round(_project(road_cam, drive, view.intr)).astype(int)
    h, w = view.size_hw
    ok = (uv[:, 0] >= 0) & (uv[:, 0] < w) & (uv[:, 1] >= 0) & (uv[:, 1] < h)
    uv, z = uv[ok], road_cam[ok, 2]
    tau_road = z / drive.ego_speed_mps[i] * compress
    for t, m in zip(thr, maps):
        outside = tau_road > t
        row[f"road_outside_{t:g}s"] = int(outside.sum())
        row[f"road_false_{t:g}s"] = int((m[uv[outside, 1], uv[outside, 0]] > 0.5).sum())


def _spearman(a: np.ndarray, b: np.ndarray) -> float:
    ra, rb = np.argsort(np.argsort(a)), np.argsort(np.argsort(b))
    return float(np.corrcoef(ra, rb)[0, 1]) if len(a) > 2 else float("nan")


def summarize(rows: list[dict], s: KittiEvalSettings, tau_range_s) -> dict:
    out: dict = {"pairs": len(rows), "strides": list(s.strides), "thresholds": {}}
    for t in s.thresholds_s:
        pred = np.array([r[f"inside_{t:g}s"] for r in rows], bool)
        truth = np.array([r[f"truth_{t:g}s"] for r in rows], bool)
        road_out = sum(r.get(f"road_outside_{t:g}s", 0) for r in rows)
        road_false = sum(r.get(f"road_false_{t:g}s", 0) for r in rows)
        out["thresholds"][f"{t:g}"] = {
            "pairs_inside_in_truth": int(truth.sum()),
            "accuracy": round(float((pred == truth).mean()), 4) if rows else None,
            "misses": int((truth & ~pred).sum()),
            "false_alarms": int((~truth & pred).sum()),
            "road_false_fence_share": round(road_false / road_out, 4) if road_out else None,
        }
    out["accuracy_per_stride"] = {
        str(k): {
            f"{t:g}": round(float(np.mean([r[f"inside_{t:g}s"] == r[f"truth_{t:g}s"] for r in sub])), 4)
            for t in s.thresholds_s
        }
        for k in s.strides
        if (sub := [r for r in rows if r["stride"] == k])
    }
    cont = [r for r in rows if "tau_hat_s" in r and tau_range_s[0] <= r["tau_eff_s"] <= tau_range_s[1]]
    if cont:
        a = np.array([r["tau_hat_s"] for r in cont])
        b = np.array([r["tau_eff_s"] for r in cont])
        ok = np.isfinite(a) & (a > 0)
        out["continuous"] = {
            "pairs": len(cont),
            "spearman": round(_spearman(a[ok], b[ok]), 4) if ok.sum() > 2 else None,
            "median_ratio": round(float(np.median(a[ok] / b[ok])), 4) if ok.any() else None,
        }
    return out


def truth_check(drive: KittiDrive, tau: np.ndarray, exported_ttc_s: np.ndarray, below_s: float = 4.0) -> dict:
    """The lidar TTC against an export's exact TTC (``bittc_truth.csv``) at exact TTC < ``below_s``."""
    m = np.isfinite(exported_ttc_s) & (exported_ttc_s > 0) & (exported_ttc_s < below_s)
    seen = m & np.isfinite(tau)
    err = np.abs(tau[seen] / exported_ttc_s[seen] - 1)
    return {
        "frames": int(m.sum()),
        "frames_with_lidar_ttc": int(seen.sum()),
        "relative_error_max": round(float(err.max()), 4) if len(err) else None,
        "relative_error_median": round(float(np.median(err)), 4) if len(err) else None,
        "below_s": below_s,
    }
