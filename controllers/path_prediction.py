"""The geofence controller's in-path prediction: per view, the fenced regions that the
tracker (``controllers.tracker``) follows, and which of them it predicts into the ego's
path.

Regions (``TrackerConfig.all_fences``): each fence's inside pixels on the rows where
that fence can be judged (the ground there lies clearly outside it:
``controllers.evidence.judged_pixels``), joined over the fences; a region stands on the
road when it reaches down to the lowest such rows of a fence (with
``TrackerConfig.turn_across``, any region counts: one that does not reach them floats,
``Track.floating``, like an oncoming car whose road shows beneath it, and predicts only
as oncoming traffic). At 50 km/h the largest fence is judged only near the horizon,
above a crossing cyclist's wheels; the smaller fences see it lower down. A region must
stand up like a road user (``_upright``): span ``min_height_m`` at the static depth of
its fence (with ``turn_across``, at the ground's depth under it where that is further;
with the oncoming rules its size is judged there too: ``evidence.fenced_blobs``,
``need_far_px``), and have an inner edge that does not slant outwards row by row like a
strip of verge that the network fenced along a fence's boundary. Parts one above the other with at most
``join_rows`` rows between them are one region: a crossing cyclist's upper body counted
in the largest fence and its wheels in a smaller one are one target, not two tracks that
swap their regions job by job. A region's inner edge is read on the largest fence that
holds part of it (``TrackerConfig.edge_from_largest``): a smaller fence's counted rows
reach lower, where a kerb line crosses its lowest row at a column that holds still.

The check (``TrackerConfig.check_views``): the wide view predicts, and the fovea, which
sees the same bearings four times finer, checks its bearing test. A wide track predicted
into the path is dropped for good when the fovea track whose inner edge lies nearest its
bearing (within ``check_tol_px`` of the wide view; one with enough regions, none of them
across the fovea's centre) fails the bearing test:
a fence's edge in the wide view can stand still for half a second on a parked truck's far
corner while its true bearing moves out by three pixels. A camera with none of the check
views (no fovea) tracks and predicts nothing unless ``TrackerConfig.predict_unchecked``
(with ``check_views`` empty, every camera predicts unchecked).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from controllers.base import Calibration
from controllers.evidence import Blob, bottom_row, fenced_blobs, inner_edge_slant, need_px
from controllers.road import ground_depth_per_row, static_depth_m
from controllers.tracker import BlobTracker, Track


class Odometry:
    """Dead reckoning of the ego's planar pose from its speed and yaw rate."""

    def __init__(self) -> None:
        self.pose = (0.0, 0.0, 0.0)
        self.t_s: float | None = None

    def update(self, t_s: float, speed_mps: float, yaw_rate_radps: float) -> tuple[float, float, float]:
        if self.t_s is not None and t_s > self.t_s:
            dt = t_s - self.t_s
            x, y, psi = self.pose
            mid = psi + 0.5 * yaw_rate_radps * dt
            self.pose = (
                x + speed_mps * dt * math.cos(mid),
                y + speed_mps * dt * math.sin(mid),
                psi + yaw_rate_radps * dt,
            )
        self.t_s = t_s
        return self.pose


class PathPrediction:
    """Regions, tracks and predictions of every view that tracks (see the module docstring)."""

    def __init__(self, cfg, cals: dict[str, Calibration]) -> None:
        self.cfg = cfg  # GeofenceConfig
        t = cfg.tracker
        self.cals = cals
        # with check views asked for, a camera that has none of them predicts nothing
        checked = t.predict_unchecked or not t.check_views or any(v in cals for v in t.check_views)
        self.views = tuple(v for v in cals if t.enabled and checked and (v in t.views or v in t.check_views))
        # views that predict: the tracker's, and with the oncoming rules the check views,
        # whose floating tracks alone predict (``floating_only``)
        self.floating_only = tuple(v for v in t.check_views if t.oncoming_rules and v not in t.views)
        self.trackers = {v: BlobTracker(t, cals[v]) for v in self.views}
        self.ground_depth = {v: ground_depth_per_row(cals[v]) for v in self.views}
        self.odometry = Odometry()
        self._seen: dict[str, list[tuple[Blob, Track]]] = {}
        # views whose regions predicted into the path this job include oncoming traffic
        # (``BlobTracker.oncoming``): a car that closes faster than the ego drives
        self.oncoming_views: set[str] = set()

    @property
    def pose(self) -> tuple[float, float, float]:
        """The ego's odometry pose (x [m], y [m], psi [rad]) at this job."""
        return self.odometry.pose

    def start_job(self, t_s: float, speed_mps: float, yaw_rate_radps: float) -> None:
        """Dead-reckon the ego's pose to this job; forget the last job's regions."""
        self.odometry.update(t_s, speed_mps, yaw_rate_radps)
        self._seen = {}
        self.oncoming_views = set()

    def observe(self, view: str, maps: np.ndarray, thr: np.ndarray, bands: list, speed_mps: float, t_s: float):
        """Extract the regions of ``view`` (sorted (K, H, W) maps of fences ``thr`` [s],
        ``bands``: each fence's counted pixels, None where the view's pair turned too far)
        and associate them with its tracks. A region stands on the road where its bottom
        reaches a fence's lowest counted rows; with ``TrackerConfig.turn_across`` one that
        does not is kept too, as floating (an oncoming car whose road lies outside the
        fences beneath it)."""
        if view not in self.views:
            return
        if bands is None or not any(b.any() for b in bands):  # nothing to judge: the tracks age
            self.trackers[view].update(t_s, self.pose, speed_mps, [])
            self._seen[view] = []
            return
        c, t, cal = self.cfg, self.cfg.tracker, self.cals[view]
        need = need_px(cal, static_depth_m(cal, speed_mps, thr[-1]), c.min_region_px, c.min_face_m2)
        # with the oncoming rules a region's size, like its height, is judged where its ground
        # lies beyond the largest fence's static depth: a car oncoming 40 m away
        far = (lambda z: need_px(cal, z, c.min_region_px, c.min_face_m2)) if t.oncoming_rules else None
        inside = np.zeros(maps.shape[1:], dtype=bool)
        touch = np.zeros_like(inside)
        parts = []  # each judged fence's counted inside pixels, from the smallest fence up
        for i in range(len(thr)) if t.all_fences else [len(thr) - 1]:
            if not bands[i].any():
                continue
            parts.append((maps[i] > c.prob_inside) & bands[i])
            inside |= parts[-1]
            lowest = bottom_row(bands[i])
            rows = slice(max(lowest - c.contact_px, 0), lowest + 1)
            touch[rows] |= bands[i][rows]
        standing = touch
        if t.turn_across:  # every region is kept; one that misses the lowest counted rows floats
            touch = inside
        depths = np.array([max(static_depth_m(cal, speed_mps, tau), 1e-6) for tau in thr])
        pad = np.ceil(cal.fx_px * t.contact_pad_m / depths)
        found = fenced_blobs(
            inside, touch, maps, thr, c.prob_inside, need, self.ground_depth[view], t.join_rows, pad, far
        )
        blobs = [b for b in found if self._upright(b, cal, speed_mps)]
        if t.edge_from_largest:
            blobs = [self._largest_fence_edge(b, parts, cal) for b in blobs]
        tracks = self.trackers[view].update(t_s, self.pose, speed_mps, blobs)
        for blob, track in zip(blobs, tracks):
            # a track of a view that predicts only floating tracks stays floating: an
            # oncoming car's region reaches the counted rows once it is near
            keep = view in self.floating_only and track.floating
            track.floating = keep or not (blob.mask & standing).any()
        self._seen[view] = list(zip(blobs, tracks))

    def predicted(self, view: str, shape: tuple[int, int], t_s: float, speed_mps: float, yaw_rate: float):
        """(H, W) bool: this job's regions of ``view`` predicted into the ego's path."""
        out = np.zeros(shape, dtype=bool)
        if view not in self.views or view not in self.cfg.tracker.views + self.floating_only:
            return out
        t, cal = self.cfg.tracker, self.cals[view]
        tracker = self.trackers[view]
        floating_only = view in self.floating_only
        for blob, track in self._seen.get(view, []):
            if floating_only and not track.floating:
                continue
            if tracker.in_path(track, t_s, self.pose, speed_mps, yaw_rate):
                # a road user's width at most: a held stretch of scenery would pass the persistence
                track.held = 1 + (t.hold_jobs if track.width_m(cal) <= t.road_user_width_m else 0)
            elif track.held > 0 and tracker.oncoming(track) and track.obs[-1].across(cal):
                track.held = 1 + t.hold_jobs  # an oncoming car predicted into the path, now ahead
            elif track.held > 0 and not tracker.closing_in(track, track.contact_time_s()):
                track.held = 0  # its bearing moves out now: nothing to hold
            if track.held > 0 and not self._refuted(view, track):
                out |= blob.mask
                if tracker.oncoming(track):
                    self.oncoming_views.add(view)
            track.held = max(track.held - 1, 0)
        return out

    def _refuted(self, view: str, track: Track) -> bool:
        """Whether a finer view sees, or once saw, the track's inner edge and finds its
        bearing moving out; a refuted track stays so (its edge may later leave that view,
        or join another region)."""
        if track.refuted:
            return True
        t, cal = self.cfg.tracker, self.cals[view]
        bearing = track.obs[-1].inner_bearing(cal)
        tol = t.check_tol_px / cal.fx_px
        for v in t.check_views:
            if v == view or v not in self._seen:
                continue
            cal_v = self.cals[v]
            near = [
                (d, other)
                for _, other in self._seen[v]
                # its inner edge on one side throughout: across the centre it has none
                if len(other.obs) >= t.min_hits and not any(o.across(cal_v) for o in other.obs)
                if (d := abs(other.obs[-1].inner_bearing(cal_v) - bearing)) <= tol
            ]
            if near:  # the nearest in bearing
                other = min(near, key=lambda x: x[0])[1]
                if not self.trackers[v].closing_in(other, other.contact_time_s()):
                    track.refuted = True
                    return True
        return False

    @staticmethod
    def _largest_fence_edge(blob: Blob, parts: list[np.ndarray], cal: Calibration) -> Blob:
        """``blob`` with its inner edge read on the pixels of the largest fence that holds
        part of it (``parts``: each fence's counted inside pixels, from the smallest fence
        up). A region across the centre keeps its extent."""
        if blob.u_left <= cal.cx_px <= blob.u_right:
            return blob
        for part in reversed(parts):
            cols = np.flatnonzero((blob.mask & part).any(axis=0))
            if cols.size:
                inner = cols.max() if blob.u_right < cal.cx_px else cols.min()
                return dataclasses.replace(blob, inner_px=float(inner))
        return blob

    def _upright(self, blob: Blob, cal: Calibration, speed_mps: float) -> bool:
        """Whether a fenced region stands up like a road user, not flat on the ground: it
        spans ``TrackerConfig.min_height_m`` at the static depth of its fence (with
        ``turn_across``, at the ground's depth under it where that is further), and its inner
        edge does not slant outwards like a strip of ground along the road."""
        t = self.cfg.tracker
        rows = np.flatnonzero(blob.mask.any(axis=1))
        depth = max(static_depth_m(cal, speed_mps, blob.tau_bound_s), 1e-6)
        if t.turn_across and blob.contact_depth_m:  # the ground under it lies further
            depth = max(depth, blob.contact_depth_m)
        if rows[-1] - rows[0] + 1 < cal.fy_px * t.min_height_m / depth:
            return False
        if blob.u_left <= cal.cx_px <= blob.u_right:  # across the centre: the corridor rule judges it
            return True
        return inner_edge_slant(blob.mask, blob.u_right < cal.cx_px) <= t.max_slant_px_per_row
