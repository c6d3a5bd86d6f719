"""A controller of your own, loaded by its file's path.

Run it (from the repository root)::

    bittc run CCRs-30 --controller examples/my_controller.py:DistanceKeeper --latency fixed:20 --out runs/mine

It reuses the geofence controller's road geometry and the flow baseline, and brakes with
a single fence whose threshold grows with speed: a deployable policy (frames, own speed,
calibration; no ground truth).
"""

from __future__ import annotations

from bittc_core.estimator import make_estimator
from controllers import BrakeCommand, Calibration, Controller, Observation
from controllers.road import corridor_columns, ground_ttc_per_row, static_depth_m


class DistanceKeeper(Controller):
    """Full braking when at least ``min_px`` corridor pixels lie inside a 1.5 s fence and
    above the road's own fence boundary; warns one job earlier."""

    name = "distance-keeper"
    needs_camera = True
    num_alphas = 1  # one threshold per job: what a device profile charges, with
    estimator_kind = "flow"  # the flow baseline's cost terms

    def __init__(self, threshold_s: float = 1.5, min_px: int = 8):
        self.threshold_s = threshold_s
        self.min_px = min_px
        self.estimator = make_estimator("flow")

    def reset(self, calibration: Calibration) -> None:
        self.cal = calibration
        self.braking = False
        self.seen = 0

    def act(self, obs: Observation, truth) -> BrakeCommand:
        tau = self.threshold_s * self.estimator.dt_s / obs.dt_s  # the same eta at the estimator's interval
        inside = self.estimator.geofence(obs.image_prev, obs.image_latest, [tau])[0] > 0.5
        rows = ground_ttc_per_row(self.cal, obs.ego_speed_mps) > 1.25 * self.threshold_s
        u0, u1 = corridor_columns(
            self.cal, self.cal.ego_width_m / 2, static_depth_m(self.cal, obs.ego_speed_mps, self.threshold_s)
        )
        n = int(inside[rows][:, u0 : u1 + 1].sum()) if obs.ego_speed_mps > 1.0 else 0
        self.seen = self.seen + 1 if n >= self.min_px else 0
        self.braking |= self.seen >= 2
        return BrakeCommand(
            decel_mps2=9.0 if self.braking else 0.0,
            warning=self.braking or self.seen >= 1,
            telemetry={"corridor_px": n},
        )
