"""``geofence-exact``: the geofence controller's policy on exact fences, an upper bound.

Not deployable: an oracle of perception. Each job the fences come from the per-pixel
ground truth instead of a network (``Controller.uses_pixel_truth``: the loop hands over
each view's exact camera-plane TTC of the latest frame, ``sim.ground_truth``): pixel p
lies inside fence tau_i when 0 < tau(p) <= tau_i. Everything after the fences (the
ground rule, the corridor, the tracker's regions and predictions, the stages, the
latency) is the deployable controller's, ``controllers.geofence``. So a case that
``geofence-exact`` avoids and ``geofence`` does not is the network's miss; one that both
miss is the policy's.

A device profile prices it as the shipped network (``estimator_kind`` "bittc", its
feature cache), so that with ``--latency profile:NAME`` only the fences differ from the
network's run; ``measured`` charges the ground truth's own lookup, a few milliseconds.

Convention: the estimator's thresholds are in its own time base (``estimator_thresholds``:
tau * dt_est / pair interval), so the exact motion in depth handed to it is that of the
pair, eta = tau / (tau + pair interval), which lies below eta_i exactly when tau <= tau_i.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from bittc_core.estimator import OracleEstimator
from bittc_core.estimator.streaming import CACHED_FRAMES
from controllers.base import BrakeCommand, Calibration, Observation
from controllers.geofence import GeofenceConfig, GeofenceController


class ExactFences(OracleEstimator):
    """The exact fences of one view, priced as the network (see the module docstring)."""

    name = "bittc"  # the family a device profile charges
    cached_frames = CACHED_FRAMES

    def fork(self) -> ExactFences:
        return ExactFences(dt_s=self.dt_s)


def pair_eta(tau_s: np.ndarray, pair_dt_s: float) -> np.ndarray:
    """(H, W) camera-plane TTC [s] of the latest frame -> the pair's motion in depth
    eta = tau / (tau + pair interval); 1 (no motion) where tau is not finite."""
    tau = np.asarray(tau_s, dtype=np.float64)
    with np.errstate(invalid="ignore", divide="ignore"):
        eta = np.where(np.isfinite(tau), tau / (tau + pair_dt_s), 1.0)
    return eta.astype(np.float32)


class ExactFenceController(GeofenceController):
    """``GeofenceController`` whose fences are exact (see the module docstring)."""

    uses_ground_truth = True
    uses_pixel_truth = True

    def __init__(self, cfg: GeofenceConfig | None = None, name: str = "geofence-exact") -> None:
        # exact fences do not depend on the pair: a shorter one adds nothing
        cfg = dataclasses.replace(cfg or GeofenceConfig(), fovea_short_pair=False)
        super().__init__(ExactFences(), cfg, name=name)

    def reset(self, calibration: Calibration) -> None:
        self._pair_dt_s = calibration.frame_dt_s * self.cfg.frame_stride
        # the wide view's warm-up call in the first reset sees no motion
        self.estimator.set_ground_truth(np.ones((calibration.height_px, calibration.width_px), np.float32))
        super().reset(calibration)

    def act(self, obs: Observation, truth) -> BrakeCommand:
        if truth is None or truth.pixels is None:
            raise RuntimeError(f"controller {self.name!r} needs the per-pixel ground truth of every view")
        for view, est in self._estimators.items():
            gt = truth.pixels.get(view)
            if gt is None:
                raise RuntimeError(f"controller {self.name!r}: no ground truth of view {view!r} at t = {obs.t_s:g} s")
            est.set_ground_truth(pair_eta(gt.tau_s, self._pair_dt_s))
        return super().act(obs, truth)
