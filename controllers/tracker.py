"""Follow fenced regions over jobs and predict which will enter the ego's path.

A pedestrian crossing ahead is inside the 1.6 s fence long before it is in the ego's
corridor, and many walk clear. The tracker decides from what the car has: the fenced
regions of each job (``controllers.evidence.Blob``), the ego's speed and yaw rate, and
the calibration. The rules and their measurements: docs/vru.md. Per job and view:

1. **Associate**: each region goes to the track whose last region's column centre is
   nearest, within ``gate_frac`` of the wider of the two (at least ``min_gate_px``);
   the others start tracks. A track without a region for ``max_missed`` jobs ends.
2. **Time and depth**: a region inside fence tau_i at t_j reaches the camera plane by
   t_j + tau_i. A track's contact time t0 is the earliest such bound over its history,
   and its depth at t_k the static depth of the TTC left then, Z_k = s cos p (t0 - t_k)
   (at least ``min_ttc_s``), re-placed with every tighter t0. Where the ground under a
   region shows (it closes faster than the ego drives: an oncoming car), that ground's
   depth is used when it is the larger.
3. **Ground motion**: each region's inner edge (the column nearest the image centre, on
   the largest fence that holds part of it: ``edge_from_largest``) at Z_k, in one
   odometry frame by dead reckoning, gives the target's velocity over the ground by a
   least-squares line over the last ``window`` jobs. A region across the centre is the
   corridor rule's (``controllers.geofence``); one cut by the image's side predicts
   nothing, unless ``cut_regions`` or ``extent``.
4. **Predict**: the ego keeps its speed and yaw rate, the target its velocity; sampled
   every ``step_s`` up to the track's TTC plus ``horizon_pad_s``, does the target (its
   inner edge, ``target_half_length_m`` along the ego; with ``extent`` also its width
   outwards) overlap the ego's footprint widened by ``margin_m`` each side? Only a track
   whose inner edge's bearing (the ego's rotation taken out) comes in or holds predicts
   (with ``corridor_allowance``, also one that moves out no faster than an edge met
   inside the corridor): beside the path a standing object's bearing moves out as the
   ego approaches, at any depth, so no error of the coarse depth can bring it in. Tracks
   with fewer than ``min_hits`` regions, a ground speed above ``max_speed_mps`` (a bad
   association) or below ``min_speed_mps`` (standing: the corridor rule judges it)
   predict nothing.
5. **Hold**: a predicted track no wider than ``road_user_width_m`` keeps counting for
   ``hold_jobs`` more jobs while its bearing still comes in
   (``controllers.path_prediction``): a crossing cyclist's few pixels of edge swing the
   fitted crossing point by metres from job to job.

With ``turn_across``: association takes out the ego's rotation since a track's last
region; a track whose region comes to lie across the image centre keeps the side it came
from, placed by its leading edge; a track whose region floats (``Track.floating``: it
does not reach a fence's lowest counted rows) predicts only when it comes towards the ego
at ``float_closing_mps`` or faster along the ego's heading when the track began
(``Track.first_psi``), and then along that heading only (oncoming traffic keeps its
lane). With ``oncoming`` as well (``BlobTracker.oncoming``), such a track may move at up
to ``oncoming_max_speed_mps``, predicts by its leading edge where the image's side cuts
its region, and is fitted on its regions with the ground's depth under them only (at
least ``min_hits``); the fovea's floating tracks predict too, and regions are sized at the
depth of the ground under them (``controllers.path_prediction``).

Odometry (``controllers.path_prediction.Odometry``): x [m] forward and y [m] left of the
ego's footprint centre at the run's start, heading psi [rad]. Camera frame to ego frame:
forward = Z + mount_forward_m, left = -X.
"""

from __future__ import annotations

import math

import numpy as np

from controllers.base import Calibration
from controllers.evidence import Blob
from controllers.track import Obs, Track
from controllers.tracker_config import TrackerConfig


class BlobTracker:
    """The tracks of one view (see the module docstring)."""

    def __init__(self, cfg: TrackerConfig, cal: Calibration) -> None:
        self.cfg, self.cal = cfg, cal
        self.tracks: list[Track] = []

    def update(self, t_s: float, pose, speed_mps: float, blobs: list[Blob]) -> list[Track]:
        """Associate this job's regions; -> the track of each region, in order."""
        c = self.cfg
        free = list(range(len(self.tracks)))
        out = []
        for b in blobs:
            centre, width = 0.5 * (b.u_left + b.u_right), b.u_right - b.u_left + 1
            best, best_d = None, math.inf
            for i in free:
                tr = self.tracks[i]
                # turning left (psi up) moves the world right in the image
                turned_px = self.cal.fx_px * (pose[2] - tr.obs[-1].pose[2]) if c.turn_across else 0.0
                d = abs(tr.centre_px + turned_px - centre)
                if d <= max(c.gate_frac * max(width, tr.width_px), c.min_gate_px) and d < best_d:
                    best, best_d = i, d
            if best is None:
                self.tracks.append(Track())
                best = len(self.tracks) - 1
            else:
                free.remove(best)
            tr = self.tracks[best]
            obs = Obs(t_s, b.u_left, b.u_right, b.tau_bound_s, b.contact_depth_m, speed_mps, pose, b.inner_px)
            tr.obs.append(obs)
            if tr.first_psi is None:
                tr.first_psi = pose[2]
            if not obs.across(self.cal):
                tr.last_side = obs.u_right < self.cal.cx_px
            del tr.obs[: -c.window]
            tr.missed = 0
            out.append(tr)
        for i in free:
            self.tracks[i].missed += 1
        self.tracks = [t for t in self.tracks if t.missed <= c.max_missed]
        return out

    def _ground_points(self, tr: Track, t0: float) -> tuple[np.ndarray, np.ndarray, float] | None:
        """(times (N,), odometry points (N, 2) of the inner edge, the latest region's extent
        [m] beyond its inner edge); None when a region lies across the image centre and
        the track's side is not known (``Track.side``), or, without ``extent``, touches
        the image's side (cut there: where it ends is not seen). An oncoming track
        (``oncoming``) is placed by its cut regions too, but only by its regions with the
        ground's depth under them, of which it needs ``min_hits``."""
        cal, c = self.cal, self.cfg
        cos_p = math.cos(math.radians(cal.pitch_deg))
        ts, pts = [], []
        side = tr.side(cal, c.turn_across)
        oncoming = self.oncoming(tr)
        for o in tr.obs:
            cut = o.u_left <= 0 or o.u_right >= cal.width_px - 1
            if (side is None and o.across(cal)) or (cut and not (c.cut_regions or c.extent or oncoming)):
                return None
            if oncoming and not o.contact_depth_m:  # its depth at the ego's speed: far too near
                continue
            z = max(o.speed_mps * cos_p * max(t0 - o.t_s, c.min_ttc_s), o.contact_depth_m or 0.0, 0.5)
            fwd, left = z + cal.mount_forward_m, -o.inner_bearing(cal, side) * z
            x, y, psi = o.pose
            pts.append((x + fwd * math.cos(psi) - left * math.sin(psi), y + fwd * math.sin(psi) + left * math.cos(psi)))
            ts.append(o.t_s)
            # the lateral extent [m] beyond the inner edge: the region's width at its depth,
            # or unbounded where the image's side cuts it (the latest region placed)
            extent = math.inf if cut else (o.u_right - o.u_left + 1) / cal.fx_px * z
        if len(ts) < c.min_hits:  # an oncoming track's regions with the ground under them
            return None
        return np.asarray(ts), np.asarray(pts), extent if c.extent else 0.0

    def oncoming(self, tr: Track) -> bool:
        """Whether ``tr`` moves by the rules for oncoming traffic (``TrackerConfig.oncoming``)."""
        return self.cfg.oncoming_rules and tr.floating

    def closing_in(self, tr: Track, t0: float) -> bool:
        """Whether the inner edge's bearing, with the ego's own rotation taken out, moves
        towards the image centre over the window, or out no faster than an edge that
        meets the camera plane inside the ego's corridor (least-squares slope).

        A target whose inner edge reaches the camera plane at a lateral offset X at t0
        has bearing X / (s (t0 - t)) + const, moving out at X / (s (t0 - t)^2): beside
        the path (|X| beyond the corridor's half width w) faster than w / (s (t0 -
        t)^2), whatever its depth. t0 is an upper bound of the contact time (the fences
        bound the TTC from above), so the allowance, taken at the window's first job, errs
        small: a standing object beside the path is never let through. A track no wider
        than a road user also holds with ``bearing_tol_px_per_s``; a wider one must come
        in or hold exactly: a long structure beside the road, fenced up to a fence's static
        depth s tau, ends at the bearing X / (s tau), which holds whatever X."""
        cal, c = self.cal, self.cfg
        ts, dist = [], []
        psi0 = tr.obs[0].pose[2]
        side = tr.side(cal, c.turn_across)
        for o in tr.obs:
            bearing = o.inner_bearing(cal, side) - (o.pose[2] - psi0)  # turning left moves the world right
            ts.append(o.t_s)
            # the distance from the centre, on the side it came from (negative past it)
            dist.append(abs(bearing) if side is None else (-bearing if side else bearing))
        ts = np.asarray(ts) - ts[0]
        if np.ptp(ts) <= 0:
            return False
        slope = float(np.polyfit(ts, dist, 1)[0])
        if slope <= 0.0:
            return True
        if tr.width_m(cal) > c.road_user_width_m:  # scenery: no allowance
            return False
        o = tr.obs[0]
        closing_mps = o.speed_mps * math.cos(math.radians(cal.pitch_deg))
        tau = max(t0 - o.t_s, c.min_ttc_s)
        allowance = (
            (cal.ego_width_m / 2 + c.margin_m) / (closing_mps * tau**2)
            if closing_mps > 0 and c.corridor_allowance
            else 0.0
        )
        return slope <= allowance + c.bearing_tol_px_per_s / cal.fx_px

    def in_path(self, tr: Track, t_s: float, pose, speed_mps: float, yaw_rate_radps: float) -> bool:
        """Whether track ``tr`` is predicted to enter the ego's widened footprint within its TTC."""
        c, cal = self.cfg, self.cal
        if len(tr.obs) < c.min_hits or speed_mps <= 0:
            return False
        t0 = tr.contact_time_s()
        if not self.closing_in(tr, t0):
            return False
        placed = self._ground_points(tr, t0)
        if placed is None:
            return False
        ts, pts, extent_m = placed
        tm = ts.mean()
        A = np.stack([np.ones_like(ts), ts - tm], axis=1)
        coef, *_ = np.linalg.lstsq(A, pts, rcond=None)
        vel = coef[1]
        top = c.oncoming_max_speed_mps if self.oncoming(tr) else c.max_speed_mps
        if not c.min_speed_mps <= float(np.hypot(*vel)) <= top:
            return False
        if c.turn_across and tr.floating:  # oncoming, keeping its lane, or nothing
            # the oncoming lane runs along the ego's heading when the track began: before the
            # turn, for a car tracked as it comes
            lane = np.array([math.cos(tr.first_psi), math.sin(tr.first_psi)])
            along = float(vel @ lane)
            if along > -c.float_closing_mps:
                return False
            vel = along * lane
        horizon = max(t0 - t_s, 0.0) + c.horizon_pad_s
        times = np.arange(0.0, horizon + 1e-9, c.step_s)
        target = coef[0] + np.outer(times + (t_s - tm), vel)  # (N, 2)
        x, y, psi = pose
        heading = psi + yaw_rate_radps * times
        if abs(yaw_rate_radps) > 1e-6:
            r = speed_mps / yaw_rate_radps
            ex = x + r * (np.sin(heading) - math.sin(psi))
            ey = y - r * (np.cos(heading) - math.cos(psi))
        else:
            ex, ey = x + speed_mps * times * math.cos(psi), y + speed_mps * times * math.sin(psi)
        dx, dy = target[:, 0] - ex, target[:, 1] - ey
        fwd = dx * np.cos(heading) + dy * np.sin(heading)
        left = -dx * np.sin(heading) + dy * np.cos(heading)
        reach_l = cal.ego_length_m / 2 + c.target_half_length_m
        reach_w = cal.ego_width_m / 2 + c.margin_m
        # the target spans from its inner edge outwards, away from the image centre, by its
        # extent (ego frame: left of the centre is + left)
        side = tr.side(cal, c.turn_across)
        last = tr.obs[-1]
        across = side is not None and last.across(cal)  # it spans out from its leading edge
        outwards = (1.0 if side else -1.0) if across else (1.0 if last.u_right < cal.cx_px else -1.0)
        far = left + outwards * extent_m  # +-inf where the image's side cuts it
        lo, hi = np.minimum(left, far), np.maximum(left, far)
        return bool(np.any((np.abs(fwd) <= reach_l) & (lo <= reach_w) & (hi >= -reach_w)))
