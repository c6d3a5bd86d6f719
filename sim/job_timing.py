"""Wall time of whole closed-loop jobs on this machine: the estimator on every view plus the
geofence controller's own work, as the loop charges them in ``measured`` mode. Used by
``bittc profile`` (the cost terms of ``sim.latency``) and ``bittc bench --fovea``.

Protocol (as ``bittc_core.benchmark``): every setting has its own controller (its own
frame caches, the model shared) and round j times call j of every setting in turn, the
order rotated each round, so a slow spell lands on all settings alike. A ``stream``
setting sees pairs (f_j, f_j+1) of a random frame sequence, so each view extracts one new
frame per job; a ``fresh`` setting sees a pair of two frames it never saw (both
extracted, as after a skip). Random frames time the same as rendered ones.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from controllers.base import Calibration, Observation
from controllers.geofence import GeofenceConfig, GeofenceController, default_thresholds
from sim.camera import CameraConfig
from sim.latency import JobWork, pixel_shares
from sim.vehicles import EGO_SIZE_M

SPEED_MPS = 20.0  # [m/s] the ego speed the controller reasons with (the corridor, the ground rule)


@dataclass(frozen=True)
class JobSetting:
    """One timed kind of job."""

    num_alphas: int  # thresholds per view (0 with ``continuous``)
    fovea_zoom: float | None = None  # None: the wide view alone
    fresh: bool = False  # both frames of the pair unseen (the re-extraction after a skip)
    continuous: bool = False  # the network's continuous TTC on every view instead of a controller job

    @property
    def views(self) -> int:
        return 1 if self.fovea_zoom is None else 2

    def calibration(self, size_hw: tuple[int, int]) -> Calibration:
        """The car of this setting: the default camera at ``size_hw`` (its fovea, if any, of
        the default width share)."""
        camera = CameraConfig(height_px=size_hw[0], width_px=size_hw[1], fovea_zoom=self.fovea_zoom)
        return Calibration.from_camera(camera, EGO_SIZE_M)

    def controller_config(self) -> GeofenceConfig:
        return GeofenceConfig(thresholds_s=default_thresholds(self.num_alphas))

    def work(self, family: str, cached: bool, size_hw: tuple[int, int] = (96, 288)) -> JobWork:
        """What the job computes, in wide-view equivalents (``sim.cost_model.JobWork``)."""
        cal = self.calibration(size_hw)
        per_view = (2 if self.fresh else 1) if cached else 0
        if self.continuous:
            counts = {v: 0 for v in cal.views}
        else:
            counts = {v: len(i) for v, i in self.controller_config().fences(cal.views).items()}
        return JobWork.of_views(counts, pixel_shares(cal), family, per_view)


def _frames(rng: np.random.Generator, size_hw: tuple[int, int], n: int) -> list[np.ndarray]:
    return [rng.integers(0, 256, (*size_hw, 3), dtype=np.uint8) for _ in range(n)]


class _Timed:
    """One setting: its controller (or continuous estimators) and its own frames."""

    def __init__(self, setting: JobSetting, estimator, size_hw, rng, n_rounds: int) -> None:
        self.s = setting
        self.cal = setting.calibration(size_hw)
        fork = getattr(estimator, "fork", None)
        if setting.continuous:
            self.ests = [fork() if fork else estimator for _ in range(setting.views)]
        else:
            self.ctrl = GeofenceController(fork() if fork else estimator, setting.controller_config())
            self.ctrl.reset(self.cal)
        n = 2 * n_rounds if setting.fresh else n_rounds + 1
        self.frames = [_frames(rng, (c.height_px, c.width_px), n) for c in self.cal.views.values()]

    def call(self, j: int) -> None:
        a, b = (2 * j, 2 * j + 1) if self.s.fresh else (j, j + 1)
        pairs = [(f[a], f[b]) for f in self.frames]
        if self.s.continuous:
            for est, (prev, latest) in zip(self.ests, pairs):
                est.continuous(prev, latest)
            return
        fovea = pairs[1] if len(pairs) > 1 else (None, None)
        obs = Observation(0.0, SPEED_MPS, pairs[0][1], pairs[0][0], 0.2, self.cal, fovea[1], fovea[0])
        self.ctrl.act(obs, None)


def time_jobs(
    estimator, settings: list[JobSetting], size_hw=(96, 288), calls: int = 30, warmup: int = 3, seed: int = 0
) -> list[float]:
    """-> the median wall time [ms] of each setting's job, in the order given."""
    rng = np.random.default_rng(seed)
    rounds = calls + warmup
    timed = [_Timed(s, estimator, size_hw, rng, rounds) for s in settings]
    times: list[list[float]] = [[] for _ in settings]
    for j in range(rounds):
        r = j % len(timed)
        for i in list(range(r, len(timed))) + list(range(r)):
            t0 = time.perf_counter()
            timed[i].call(j)
            if j >= warmup:
                times[i].append(time.perf_counter() - t0)
    return [round(float(np.median(t) * 1e3), 3) for t in times]


def profile_settings(family: str, fovea_zoom: float = 4.0) -> list[JobSetting]:
    """The jobs ``bittc profile`` times for one estimator family: enough variety in
    extractions, views and thresholds to tell the four cost terms apart."""
    if family == "flow":
        return [JobSetting(k, z) for z in (None, fovea_zoom) for k in (1, 4, 16)]
    return [
        *(JobSetting(k) for k in (1, 2, 4, 8, 16)),
        *(JobSetting(k, fovea_zoom) for k in (1, 4, 16)),
        JobSetting(1, fresh=True),
        JobSetting(8, fresh=True),
        JobSetting(4, fovea_zoom, fresh=True),
    ]
