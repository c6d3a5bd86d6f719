"""Staged AEB on the exact TTC of the actors in the ego's path: the upper bound.

The stages of :mod:`controllers.stages` on the exact bumper-to-bumper TTC, gap and
closing speed of the critical actor (the in-path actor ahead with the smallest TTC),
read from ground truth. Braking is released once no in-path actor closes in.

Where paths cross (road users, junctions: ``sim.path_truth``), the contact time alone
can come too late: a car crossing the ego's path hits an ego that stopped in its way. There
the oracle also brakes fully at the last moment at which full braking still keeps the
footprints apart (``must_brake``), whatever the TTC.
"""

from __future__ import annotations

from controllers.base import BrakeCommand, Controller, Observation
from controllers.stages import StageConfig, StagedBrake

OracleConfig = StageConfig  # the oracle's settings are the stages themselves


class OracleController(Controller):
    name = "oracle"
    uses_ground_truth = True

    def __init__(self, cfg: StageConfig | None = None):
        self.cfg = cfg or StageConfig()
        self._stages = StagedBrake(self.cfg)

    def reset(self, calibration=None) -> None:
        self._stages.reset()

    def act(self, obs: Observation, truth) -> BrakeCommand:
        c = self.cfg
        crit = truth.critical
        if crit is None or crit.ttc_s == float("inf"):
            return self._stages.release()
        ttc, gap, v_rel = crit.ttc_s, max(crit.gap_m, 0.01), crit.closing_speed_mps
        required = v_rel**2 / (2 * gap)
        full = ttc <= c.full_ttc_s or crit.must_brake
        return self._stages.update(ttc <= c.warn_ttc_s or full, ttc <= c.partial_ttc_s, full, required)
