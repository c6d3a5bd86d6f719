"""The one closed-loop core: clock, frame schedule, latency, command queue, end of run.

``bittc run`` / ``bittc suite`` (``sim.runner``), the benchmark and the Gymnasium env
(``sim.env``) all drive a scenario through :class:`ClosedLoop`, so that latency, frame
skipping, the actuator and the end of a run behave the same everywhere.

Time: the traffic integrates at ``ScenarioSim.sim_dt_s`` (100 Hz); the camera captures
frame k at t_k = k * dt (every frame: only computation is ever skipped). Jobs follow the
streaming schedule of :mod:`sim.latency`: a job on frame k starts at t_start, pairs frame
k with frame k - stride, and its command takes effect at t_start + L (rounded up to the
next traffic step); the actuator's delay follows. Commands are applied in the order they
take effect (``sim.latency.CommandQueue``). The run ends as :meth:`ScenarioSim.done`
says, checked at every frame boundary. With a fovea (``camera.fovea_zoom``) every frame
is captured in both views and a job's observation carries both pairs.

Frame status: ``processed`` (a job ran on it), ``skipped`` (captured while the estimator
was busy, and a newer frame was taken), ``unpaired`` (captured before the first frame
that has a partner ``frame_stride`` frames back: nothing was busy), ``unused`` (the run
ended first). ``frames_skipped`` counts only the skipped ones.

Usage (what ``drive`` does)::

    loop = ClosedLoop(sim, parse_latency("fixed:50"), num_alphas=4, pairs=True)
    job = loop.reset()
    while job is not None:
        cmd = policy(loop.observation(job))
        job = loop.submit(cmd, compute_s)   # None once the run has ended
"""

from __future__ import annotations

import math
import time
from collections import defaultdict
from collections.abc import Callable
from dataclasses import replace

import cv2

from controllers.base import BrakeCommand, Calibration, Controller, Observation
from sim.episode import Frame, ScenarioSim, StepTruth
from sim.episode_records import FrameRecord
from sim.fence_lag import FenceLagMeter
from sim.ground_truth import GroundTruth
from sim.latency import (
    TIME_EPS_S,
    CommandQueue,
    FeatureCacheModel,
    Job,
    JobWork,
    LatencyError,
    LatencyMode,
    next_job,
    pixel_shares,
)
from sim.vehicles import EGO_SIZE_M

cv2.setNumThreads(1)  # OpenCV's own pool would contend with the estimator's torch threads


class ClosedLoop:
    """One run of ``sim`` under a latency mode (see the module docstring).

    Args:
        sim: the scenario run (rendering when ``pairs`` or a capture hook needs frames).
        latency: how each job's latency is charged.
        num_alphas: thresholds per view per job (what a device profile charges, times ``views``).
        pairs: jobs need an image pair: the first job is on frame ``frame_stride``.
        estimator: the estimator family a profile prices (``sim.latency.COST_FAMILIES``), None for none.
        views: camera views the estimator runs on per job.
        cached_frames: frames the estimator's feature cache holds per view (0: no cache).
        ``drive`` takes the last four from the controller.
        frame_stride: the pair is (frame k - stride, frame k).
        on_capture: called with (record, frame) after every capture (videos).
        lag_meter: measures the fence lag of the critical actor from each job's geofences.
    """

    def __init__(
        self,
        sim: ScenarioSim,
        latency: LatencyMode,
        *,
        num_alphas: int = 0,
        pairs: bool = False,
        frame_stride: int = 1,
        on_capture: Callable[[FrameRecord, Frame], None] | None = None,
        lag_meter: FenceLagMeter | None = None,
        estimator: str | None = None,
        views: int = 1,
        cached_frames: int = 0,
    ) -> None:
        if not isinstance(frame_stride, int) or frame_stride < 1:
            raise ValueError(f"frame_stride = {frame_stride!r}: must be an integer >= 1")
        self.sim = sim
        self.latency = latency
        self.num_alphas = int(num_alphas)
        self.pairs = pairs
        self.stride = frame_stride
        self.on_capture = on_capture
        self.lag_meter = lag_meter
        self.estimator, self.cached_frames = estimator, int(cached_frames)
        self.frame_dt_s = sim.camera.dt_s
        self.calibration = Calibration.from_camera(sim.camera, EGO_SIZE_M)
        # view -> thresholds per job (``drive`` takes them from the controller)
        self.view_thresholds = {v: self.num_alphas for v in tuple(self.calibration.views)[: int(views)]}
        self._pixel_share = pixel_shares(self.calibration)
        self.timing: dict[str, float] = defaultdict(float)  # [s] wall time per phase

    # ------------------------------------------------------------------ public
    def reset(self) -> Job:
        """Start the run; -> the first job."""
        self.truth = self.sim.reset()
        self.queue = CommandQueue(BrakeCommand())
        self.records: list[FrameRecord] = []
        self._frames: dict[int, Frame] = {}
        self._gt: dict[int, GroundTruth] = {}
        self._substeps = 0
        self.end_reason: str | None = None
        self.first_warning: tuple[float, float | None] | None = None  # (t [s], critical TTC [s])
        self.first_brake: tuple[float, float | None] | None = None
        self.brake_integral = 0.0  # [m/s] integral of the commanded deceleration over time
        # each view's feature cache as the loop counts it (alike while the views read the same frames)
        self._caches = {v: FeatureCacheModel(self.cached_frames) for v in self._pixel_share}
        self._first_frame = self.stride if self.pairs else 0
        self._capture()
        return self._schedule(-1, 0.0)

    def observation(self, job: Job) -> Observation:
        rec = self.records[job.frame]
        latest = self._frames.get(job.frame)
        prev = self._frames.get(job.frame - self.stride) if self.pairs else None
        fovea = (latest.fovea, prev.fovea if prev is not None else None) if latest is not None else (None, None)
        # the fovea one frame interval before the latest, for a controller that reads a shorter pair too
        short = self._frames.get(job.frame - 1) if self.pairs and self.stride > 1 and fovea[0] is not None else None
        return Observation(
            rec.t_s,
            rec.ego_speed_mps,
            latest.image if latest is not None else None,
            prev.image if prev is not None else None,
            self.stride * self.frame_dt_s,
            self.calibration,
            fovea[0].rgb if fovea[0] is not None else None,
            fovea[1].rgb if fovea[1] is not None else None,
            rec.ego_yaw_rate_radps,
            self._pair_yaw_rad(job.frame) if prev is not None else None,
            short.fovea.rgb if short is not None and short.fovea is not None else None,
            self._pair_yaw_rad(job.frame, 1) if short is not None else None,
        )

    def _pair_yaw_rad(self, frame: int, stride: int | None = None) -> float:
        """[rad] + left: the ego's heading change from frame ``frame - stride`` (default the
        loop's) to ``frame``."""
        turn = self.records[frame].ego_heading_rad - self.records[frame - (stride or self.stride)].ego_heading_rad
        return math.remainder(turn, math.tau)

    def truth_at(self, job: Job) -> StepTruth:
        """Ground truth at the job's capture (for oracles, ``info`` and traces only)."""
        return self.records[job.frame].truth

    def ground_truth(self, frame: int, view: str = "wide") -> GroundTruth | None:
        """Per-pixel ground truth of ``frame`` against the frame before in view 'wide' or
        'fovea' (None without images, or without that view)."""
        key = (frame, view)
        if key not in self._gt:
            prev, latest = self._frames.get(frame - 1), self._frames.get(frame)
            if prev is None or latest is None or latest.view(view)[1] is None:
                return None
            t0 = time.perf_counter()
            self._gt[key] = self.sim.ground_truth(prev, latest, view)
            self.timing["ground_truth_s"] += time.perf_counter() - t0
        return self._gt[key]

    def submit(self, cmd: BrakeCommand, compute_s: float, who: str = "controller") -> Job | None:
        """The command decided in the current job, which took ``compute_s`` of wall time;
        -> the next job, or None when the run has ended."""
        cmd.check(who)
        job = self._job
        work = self._work(job.frame, cmd)
        L = self.latency.latency_s(compute_s, work)
        rec = self.records[job.frame]
        rec.status, rec.latency_s, rec.wait_s, rec.decided, rec.work = "processed", L, job.wait_s, cmd, work
        self.queue.push(job.start_s + L, job.frame, cmd)
        views = cmd.views()
        if self.lag_meter is not None and views and rec.truth.critical is not None:
            gts = {name: self.ground_truth(job.frame, name) for name in views}
            rec.fence_cover = self.lag_meter.update(views, gts, rec.truth.critical)
        return self._schedule(job.frame, job.start_s + L)

    def _work(self, frame: int, cmd: BrakeCommand) -> JobWork:
        """What the job on ``frame`` computes: the frames not in each view's feature cache (its
        pair's, then the shorter pair's of telemetry ``short_pair``), and one more frame per
        warped earlier frame (``derotated``, a derotated shorter pair: no cache holds one)."""
        pair = (frame - self.stride, frame) if self.pairs else (frame,)
        tags = filter(None, str(cmd.telemetry.get("short_pair", "")).split("+"))
        shorts = {t.removesuffix("-derotated"): t.endswith("-derotated") for t in tags}
        warped = [v for v in str(cmd.telemetry.get("derotated", "")).split("+") if v in self._pixel_share]
        warped += [v for v, rotated in shorts.items() if rotated and v in self._pixel_share]
        counts = {}
        for v, cache in self._caches.items():  # the frames in the order the estimator reads them
            read = pair + ((frame - 1, frame) if v in shorts and not shorts[v] else ())
            counts[v] = cache.extractions(read)
        n = counts["wide"]
        work = JobWork.of_views(self.view_thresholds, self._pixel_share, self.estimator, n)
        extra = sum((counts[v] - n) * self._pixel_share[v] for v in self.view_thresholds) + sum(
            self._pixel_share[v] for v in warped
        )
        return replace(work, extractions=work.extractions + extra) if extra else work

    def drive(self, controller: Controller) -> None:
        """Run to the end with ``controller`` deciding every job (reset with this car's calibration)."""
        controller.reset(self.calibration)
        if self.latency.kind == "profile" and controller.needs_camera and controller.estimator_kind is None:
            raise LatencyError(
                f"latency {self.latency}: controller {controller.name!r} does not say which estimator family the "
                "profile should charge: set its estimator_kind ('bittc' or 'flow')"
            )
        self.estimator = controller.estimator_kind
        self.cached_frames = controller.cached_frames
        self.view_thresholds = dict(controller.view_thresholds)
        job = self.reset()
        while job is not None:
            obs = self.observation(job)
            truth = self.truth_at(job) if controller.uses_ground_truth else None
            if truth is not None and controller.uses_pixel_truth:
                truth = replace(truth, pixels={v: self.ground_truth(job.frame, v) for v in controller.views})
            t0 = time.perf_counter()
            cmd = controller.act(obs, truth)
            dt = time.perf_counter() - t0
            self.timing["controller_s"] += dt
            job = self.submit(cmd, dt, controller.name)

    @property
    def processed(self) -> list[FrameRecord]:
        return [r for r in self.records if r.status == "processed"]

    # ------------------------------------------------------------------ internals
    def _schedule(self, last_frame: int, t_free_s: float) -> Job | None:
        k, start = next_job(last_frame, t_free_s, self.frame_dt_s, self._first_frame)
        self._advance_to(start)
        for r in self.records[max(last_frame + 1, 0) : k]:
            if r.status == "pending":
                r.status = "unpaired" if r.index < self._first_frame else "skipped"
        if self.end_reason is not None:
            for r in self.records:
                if r.status == "pending":
                    r.status = "unused"
            self._frames.clear()
            return None
        self._job = Job(k, self.records[k].t_s, max(start, self.records[k].t_s))
        return self._job

    def _advance_to(self, t_s: float) -> None:
        sim = self.sim
        while self.end_reason is None and sim.t_s < t_s - TIME_EPS_S:
            self._apply_due()
            t0 = time.perf_counter()
            sim.substep(self.queue.active.decel_mps2)
            self.timing["traffic_s"] += time.perf_counter() - t0
            self.brake_integral += self.queue.active.decel_mps2 * sim.sim_dt_s
            self._substeps += 1
            if self._substeps % sim.n_sub == 0:
                t0 = time.perf_counter()
                self.truth = sim.truth()
                self.end_reason = sim.done(self.truth)
                self.timing["truth_s"] += time.perf_counter() - t0
                if self.end_reason is None:
                    self._capture()

    def _apply_due(self) -> None:
        if not self.queue.update(self.sim.t_s):
            return
        a = self.queue.active
        if a.warning and self.first_warning is None:
            self.first_warning = (self.sim.t_s, _critical_ttc(self.sim))
        if a.decel_mps2 > 0 and self.first_brake is None:
            self.first_brake = (self.sim.t_s, _critical_ttc(self.sim))

    def _capture(self) -> None:
        self._apply_due()
        sim = self.sim
        t0 = time.perf_counter()
        frame = sim.capture()
        self.timing["render_s"] += time.perf_counter() - t0
        rec = FrameRecord(
            len(self.records),
            sim.t_s,
            float(sim.ego.speed),
            float(sim.ego.current_accel_mps2),
            self.truth,
            self.queue.active,
            ego_yaw_rate_radps=float(sim.ego.yaw_rate_radps),
            ego_heading_rad=sim.ego.world_pose()[2],
        )
        self.records.append(rec)
        self._frames[rec.index] = frame
        for k in [k for k in self._frames if k < rec.index - self.stride - 1]:
            del self._frames[k]
        for k in [k for k in self._gt if k[0] < rec.index - self.stride - 1]:
            del self._gt[k]
        if self.on_capture is not None:
            self.on_capture(rec, frame)


def _critical_ttc(sim: ScenarioSim) -> float | None:
    c = sim.truth().critical
    return c.ttc_s if c is not None and math.isfinite(c.ttc_s) else None
