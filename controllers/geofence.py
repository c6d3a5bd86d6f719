"""Geofence controllers: staged AEB driven by an estimator's K temporal geofences.

Deployable: reads the two frames of its pair, the ego's own speed and the car's
calibration (``controllers.base.Calibration``); never ground truth. The estimator is any
``bittc_core.estimator.Estimator`` (``geofence``: the shipped network; ``flow``: DIS +
affine expansion), built once and reset per run.

Each job, for every fence tau_i (camera-plane TTC [s] from the latest frame; the
estimator's map p_i = p(0 < tau <= tau_i)):

1. **Inside**: pixels with p_i > ``prob_inside``.
2. **Not the road**: the static ground ahead has a finite TTC, tau_ground(row) = Z(row)
   / (s cos p) (``controllers.road``; turning, per pixel: ``controllers.evidence``; at
   50 km/h the road within about 33 m lies inside a 2.4 s fence). A pixel counts only on
   rows whose ground lies clearly outside the fence, tau_ground(row) > ``ground_margin``
   * tau_i: an obstacle standing on the road reaches the camera plane sooner than the
   road under its upper part. At standstill tau_ground is +inf: every inside pixel
   counts (a static world is at tau = inf and inside no fence). Optionally (off by
   default) the estimator's own road edge bounds them too: only rows more than
   ``road_edge_rows`` rows above the row where the fence's run of inside pixels up from
   the image's bottom ends count (the median over the columns, where a tenth of them
   have such a run; ``controllers.evidence.judged_pixels``), and rows whose ground lies
   outside the fence by ``road_edge_cap``. A network that reads the road as closing
   faster than it does fences it past the boundary, and bumps along that edge stand in
   the corridor like obstacles (docs/pair_interval.md).
3. **In the corridor, or predicted into it**: the ego's width plus ``corridor_margin_m``
   on each side, along its path (straight, or bent by its yaw rate:
   ``controllers.evidence``), projected at the depth Z_i = s cos p tau_i of a static
   point on the fence. Or a fenced region anywhere across the view that the tracker
   (``controllers.path_prediction``, ``controllers.tracker``: regions followed over jobs,
   their motion over the ground, the ego's path ahead, the fovea's finer bearings)
   predicts into the ego's footprint within its TTC: a pedestrian stepping out, a car
   crossing a junction, a van merging from the next lane, an oncoming car the ego turns
   across. An actor inside the fence is at most that far if it does not close faster than
   the ego drives, so an adjacent-lane car (static, slower or same-direction) lies outside
   these columns; an oncoming car in the next lane could enter them only when its closing
   speed exceeds about 2.4x the ego's (3.5 m lanes). A car cutting in enters the columns
   as it enters the lane.
4. **Standing on the road, big enough**: an obstacle inside the fence stands on the
   road nearer than the fence's ground boundary, so its counted pixels reach down to
   the lowest counted row; a region whose bottom ends more than ``contact_px`` rows
   above it (the textureless sky, a far tree top) does not count (but for a region the
   tracker predicts, with ``TrackerConfig.turn_across``, that is as tall and as big as
   the largest fence asks at its depth: ``controllers.evidence``). The largest such
   8-connected region must have at least ``min_region_px`` pixels, and at least the
   area that ``min_face_m2`` of face covers at the fence's depth Z_i,
   fx fy A / Z_i^2 (a 1.7 x 1.5 m target at 53 m covers about 6 x 5 px; 0.3 m^2 at
   18 m is 30 px: a far target that the network puts into a near fence is too small
   for it). In the views of ``min_height_views`` (the fovea) it must also span
   ``min_height_m`` at Z_i, fy h / Z_i rows: the road's own fence, running a little past the
   counted rows' boundary, leaves strips one to five rows tall along the lowest counted row.
   Rows count only when the ground one row below them is outside the fence too.
   A view whose pair turned by more than ``max_rotation_px`` (the fastest yaw rate within
   the pair x its interval x focal length: a junction turn) moves beyond the flow the
   estimator reads. With ``derotate`` its earlier frame is first warped by the ego's
   rotation over the pair (``controllers.derotate``), and only the tracker's predicted
   regions count in that job: crossing traffic, which closes faster than the ego, lies off
   the bent corridor at a fence's static depth. Without it the view gives no evidence then.
5. **Nested** (``nested``): what lies inside tau_i lies inside every larger fence too,
   so a fence's region counts only when some larger fence has one in the same job (the
   largest fence stands alone). A far vehicle that the network reads into a middle
   fence but not into the larger ones is noise.
6. **Persistent**: the fence fires after ``persistence_frames`` consecutive jobs with
   such a region.

**From the K fences to the stages** (``controllers.stages``, thresholds in bumper-to-
bumper TTC, as the oracle's). The estimate tau_hat is the smallest threshold whose fence
fires (the true TTC is at most that). The network's tau counts to the camera plane; the
front bumper lies ``calibration.bumper_ahead_m`` ahead of it, which a static obstacle
covers in d / s seconds, so a stage threshold T becomes the camera-plane threshold
T + d / s. Each stage is assigned the fence whose threshold is nearest to that in log
tau, and is reached when tau_hat <= the assigned threshold. With K = 1 every stage
shares the one fence: warn and brake on it. The required deceleration for a static
obstacle, s / (2 (tau_hat - d / s)), picks partial or full braking at the partial
stage (``controllers.stages.fence_stages``). That formula assumes an obstacle that closes
at the ego's speed; with ``oncoming_full``, where the view whose fence gave tau_hat holds a
region of oncoming traffic that the tracker predicts into the path
(``controllers.tracker.BlobTracker.oncoming``: a car closing faster than the ego drives,
which braking avoids only by stopping short of its lane), the partial stage brakes
fully (``stage`` telemetry ``full-oncoming``). Braking latches; it is released after
``release_frames`` jobs with no fence firing, and with ``hold_to_contact`` not before the
contact time that its last firing bounded (that job's time + tau_hat): a target near
enough to fill a view may fail every test above while it is still ahead. Below
``min_speed_mps`` the controller neither warns nor brakes.

**Frame stride** (``frame_stride``, default ``DEFAULT_FRAME_STRIDE`` = 3): the pair is the
latest frame and the one captured three frames before it (0.3 s at 10 Hz): a target's
outline moves three times as far per pair at no extra compute (the estimator caches every
frame's features). The network's error in eta is roughly fixed, while 1 - eta = pair
interval / (tau + pair interval) shrinks with tau: a wider pair keeps the far fences
steady (docs/fovea_training.md, ``docs/controller_levers.py``).

**Two views** (a calibration with a ``fovea``): the same rules run on each view with its
own calibration and estimator cache; tau_hat is the smallest threshold fired in either
view. ``fovea_fences_from_s`` keeps the fences below it on the wide view only (by default
under 1.4 s: at K = 4 the fovea runs the 1.84 and 2.8 s fences; docs/fovea.md). With
``fovea_short_pair`` the fovea's smallest fence is also read on the pair one frame apart,
where a crossing road user moves a third as far (``controllers.short_pair``).

**Thresholds**: explicit (any order, within the estimator's trained range), or
``default_thresholds(K)``: K values uniform in log tau over ``DEFAULT_TAU_RANGE_S``
(0.8-2.8 s; K = 1: 1.5 s). On a pair n frame intervals long a threshold tau asks the
estimator for the same eta = tau / (tau + n dt) as tau * dt_est / (n dt).
"""

from __future__ import annotations

import math
import time

import numpy as np

from bittc_core.errors import ConfigError
from controllers.base import BrakeCommand, Calibration, Controller, GeofenceView, Observation
from controllers.derotate import derotate
from controllers.evidence import in_path_evidence, judged_bands
from controllers.geofence_config import (  # noqa: F401  (re-exported: the controller's settings)
    DEFAULT_FOVEA_FENCES_FROM_S,
    DEFAULT_FRAME_STRIDE,
    DEFAULT_TAU_RANGE_S,
    MAX_FRAME_STRIDE,
    MAX_THRESHOLDS,
    GeofenceConfig,
    check_frame_stride,
    check_thresholds,
    default_thresholds,
    estimator_thresholds,
    frame_stride_ok,
)
from controllers.path_prediction import PathPrediction
from controllers.short_pair import read_fences
from controllers.stages import StagedBrake, fence_stages, fired_fences


class GeofenceController(Controller):
    """Staged AEB on the geofences of ``estimator`` (see the module docstring)."""

    needs_camera = True

    def __init__(self, estimator, cfg: GeofenceConfig | None = None, name: str = "geofence") -> None:
        self.estimator = estimator
        self.cfg = cfg or GeofenceConfig()
        if self.cfg.fovea_short_pair and not getattr(estimator, "sources_per_threshold", False):
            msg = "would read the shorter pair in a call of its own; only the torch network reads both in one"
            raise ConfigError(f"GeofenceConfig.fovea_short_pair: estimator {getattr(estimator, 'name', '')!r} {msg}")
        self.name = name
        self.num_alphas = len(self.cfg.thresholds_s)
        self.frame_stride = self.cfg.frame_stride
        self.estimator_kind = getattr(estimator, "name", None) or None  # the family a device profile prices
        self.cached_frames = int(getattr(estimator, "cached_frames", 0))
        self._order = np.argsort(self.cfg.thresholds_s)  # fences from the smallest threshold up
        self._thr = np.asarray(self.cfg.thresholds_s, dtype=np.float64)[self._order]
        self._stages = StagedBrake(self.cfg.stages)
        self._estimators = {"wide": estimator}  # one per view: each its own frame cache
        self.cal: Calibration | None = None
        self._warm = False

    @property
    def view_thresholds(self) -> dict[str, int]:
        if self.cal is None:
            return {"wide": self.num_alphas}
        return {v: len(f) + (v == self._short_view) for v, f in self._fences.items()}

    def reset(self, calibration: Calibration) -> None:
        self.cal = calibration
        self._cals = calibration.views
        self.views = tuple(self._cals)
        self._thr_est = estimator_thresholds(self.estimator, self._thr, calibration.frame_dt_s, self.frame_stride)
        # fence indices (into the sorted thresholds) evaluated per view
        self._fences = self.cfg.fences(self._cals)
        # the view whose smallest fence is also read on the pair one frame apart (short_pair)
        short = self.cfg.fovea_short_pair and self.frame_stride > 1 and "fovea" in self._fences
        self._short_view = "fovea" if short else None
        if short:
            small = self._thr[self._fences["fovea"][:1]]
            self._thr_short = float(estimator_thresholds(self.estimator, small, calibration.frame_dt_s, 1)[0])
        if "fovea" in self._cals:
            if "fovea" not in self._estimators:
                fork = getattr(self.estimator, "fork", None)
                self._estimators["fovea"] = fork() if fork is not None else self.estimator
        if not self._warm:  # the first call of a network pays one-off costs no deployed system pays per frame
            blank = np.zeros((calibration.height_px, calibration.width_px, 3), np.uint8)
            self.estimator.geofence(blank, blank + 1, self._thr_est)
            self._warm = True
        for est in self._estimators.values():
            if hasattr(est, "reset"):
                est.reset()
        self._stages.reset()
        self._paths = PathPrediction(self.cfg, {v: self._cals[v] for v in self._fences})
        self._yaws: list[tuple[float, float]] = []  # (t [s], |yaw rate| [rad/s]) of the recent jobs
        self._streak = {v: np.zeros(len(f), dtype=np.int64) for v, f in self._fences.items()}
        self._quiet = self.cfg.release_frames  # nothing to hold at the start
        self._last = BrakeCommand()
        self._contact_by_s = -math.inf  # [s] the last braking stage's bound on the contact time

    def _estimate(self, obs: Observation, s: float, yaw: float) -> tuple[dict, float, list[str], list[str]]:
        """Every view's geofences and counted pixels, its regions handed to the tracker
        first (the fovea checks the wide view's) -> (view -> (maps, counted pixels per
        fence or None, whether the corridor rule holds), estimator time [ms], the views
        whose earlier frame was derotated: the network extracted it anew, the views that
        read the shorter pair too)."""
        c = self.cfg
        # the pair's rotation: the fastest yaw rate of the jobs within it, times its interval
        self._yaws = [(t, w) for t, w in self._yaws if t >= obs.t_s - obs.dt_s - 1e-6] + [(obs.t_s, abs(yaw))]
        turn_rad = max(w for _, w in self._yaws) * obs.dt_s
        est_ms, jobs, derotated, shorts = 0.0, {}, [], []
        for v, idx in self._fences.items():
            prev, latest = obs.pair(v)
            if latest is None or prev is None:
                raise ValueError(f"controller {self.name!r}: the observation has no {v} pair")
            t0 = time.perf_counter()
            turned = turn_rad * self._cals[v].fx_px > c.max_rotation_px
            # a turned view is derotated only where its tracker can use it: the network then
            # sees the translation alone, and so does the ground
            rotate = turned and c.derotate and v in self._paths.views
            if rotate:
                prev = derotate(prev, latest, self._cals[v], obs.pair_rotation_rad)
                derotated.append(v)
            # a view that turned too far unrotated gives no evidence: it reads no shorter pair either
            short_thr = self._thr_short if v == self._short_view and (rotate or not turned) else None
            maps, tag = read_fences(
                self._estimators[v], obs, v, prev, self._cals[v], c, rotate, self._thr_est[idx], short_thr
            )
            shorts += [tag] if tag else []
            est_ms += (time.perf_counter() - t0) * 1e3
            # where it turned, the ground of a derotated pair has the translation alone
            w = 0.0 if turned else yaw
            bands = None if turned and not rotate else judged_bands(self._cals[v], maps, self._thr[idx], s, w, c)
            jobs[v] = (maps, bands, not turned)
            # a view that turned too far without derotation gives none: its tracks age by a job
            self._paths.observe(v, maps, self._thr[idx], bands, s, obs.t_s)
        return jobs, est_ms, derotated, shorts

    def act(self, obs: Observation, truth) -> BrakeCommand:
        if self.cal is None:
            raise RuntimeError("call reset(calibration) before act()")
        c, s = self.cfg, float(obs.ego_speed_mps)
        yaw = float(obs.ego_yaw_rate_radps)
        self._paths.start_job(obs.t_s, s, yaw)
        jobs, est_ms, derotated, shorts = self._estimate(obs, s, yaw)
        tel: dict = {}
        views: dict[str, GeofenceView] = {}
        fired_at: dict[str, float] = {}  # view -> smallest fired threshold [s]
        for v, idx in self._fences.items():
            thr = self._thr[idx]
            maps, bands, static = jobs[v]
            if bands is None:
                self._streak[v][:] = 0
                empty = np.zeros(maps.shape[1:], dtype=bool)
                sizes, counted, corridor, n_pred = np.zeros(len(thr), dtype=np.int64), empty, empty, 0
            else:
                predicted = self._paths.predicted(v, maps.shape[1:], obs.t_s, s, yaw)
                tall = c.min_height_m if v in c.min_height_views else 0.0
                sizes, counted, corridor = in_path_evidence(
                    maps, thr, bands, self._cals[v], c, s, yaw, predicted, tall, static
                )
                n_pred = int(predicted.any())
            tel[f"predicted_{v}"] = n_pred
            fired, self._streak[v] = fired_fences(sizes, self._streak[v], c)
            if fired.any():
                fired_at[v] = float(thr[np.argmax(fired)])
            tag = "" if v == "wide" else f"{v}_"
            for tau, n in zip(thr, sizes):
                tel[f"inpath_px_{tag}{tau:g}s"] = int(n)
            views[v] = GeofenceView(tuple(float(t) for t in thr), maps, counted, corridor)
        tau_hat = min(fired_at.values()) if fired_at else None
        fired_views = {v for v, t in fired_at.items() if t == tau_hat}
        if s < c.min_speed_mps:
            cmd, stage = self._stages.release(), "standstill"
        elif tau_hat is None:
            self._quiet += 1
            # braking holds until the contact time its last firing bounded has passed
            free = self._quiet >= c.release_frames and not (c.hold_to_contact and obs.t_s < self._contact_by_s)
            cmd = self._stages.release() if free else self._last
            stage = "none" if free else "hold"
        else:
            self._quiet = 0
            reached, required = fence_stages(self._thr, tau_hat, s, self.cal.bumper_ahead_m, c.stages)
            # an oncoming car closes faster than the static obstacle that ``required`` assumes
            oncoming = (
                c.oncoming_full and reached[1] and not reached[2] and bool(self._paths.oncoming_views & fired_views)
            )
            reached[2] = reached[2] or oncoming
            cmd = self._stages.update(*reached, required)
            if cmd.decel_mps2 > 0:
                self._contact_by_s = max(self._contact_by_s, obs.t_s + tau_hat)
            stage = "full" if reached[2] else "partial" if reached[1] else "warn" if reached[0] else "fence"
            stage += "-oncoming" if oncoming else ""
        tel = {
            "estimator_ms": round(est_ms, 3),
            "fence_fired_s": tau_hat if tau_hat is not None else "",
            "fired_view": "+".join(v for v in self._fences if v in fired_views),
            "derotated": "+".join(derotated),  # views whose earlier frame the network extracted anew
            "short_pair": "+".join(shorts),  # views whose smallest fence read the pair one frame apart too
            "stage": stage,
            **tel,
        }
        self._last = BrakeCommand(cmd.decel_mps2, cmd.warning)
        return BrakeCommand(
            cmd.decel_mps2, cmd.warning, telemetry=tel, view=views["wide"], fovea_view=views.get("fovea")
        )
