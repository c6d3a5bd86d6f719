"""Staged AEB on the exact TTC of the actors in the ego's path: the upper bound.

Stages, as production AEB systems stage them (Euro NCAP / UN R152 style):
  1. forward-collision warning when TTC <= ``warn_ttc_s`` (2.4 s, above NHTSA's
     2.1 s minimum for a stopped lead at 72 km/h);
  2. partial braking at ``partial_decel_mps2`` when TTC <= ``partial_ttc_s`` (1.6 s);
  3. full braking when TTC <= ``full_ttc_s`` (0.9 s), or earlier when the constant
     deceleration needed to stop the closing, gap^2-wise (v_rel^2 / (2 gap)), exceeds
     what partial braking gives.
Braking latches: once engaged it is never reduced while the critical actor still
closes in, and it is released once no in-path actor closes in.
"""

from __future__ import annotations

from dataclasses import dataclass

from controllers.base import BrakeCommand, Controller, Observation


@dataclass(frozen=True)
class OracleConfig:
    warn_ttc_s: float = 2.4  # [s]
    partial_ttc_s: float = 1.6  # [s]
    full_ttc_s: float = 0.9  # [s]
    partial_decel_mps2: float = 4.0  # [m/s^2]
    full_decel_mps2: float = 9.0  # [m/s^2]
    required_decel_margin: float = 0.8  # full braking when v_rel^2/(2 gap) > margin * partial decel [-]


class OracleController(Controller):
    name = "oracle"
    uses_ground_truth = True

    def __init__(self, cfg: OracleConfig | None = None):
        self.cfg = cfg or OracleConfig()
        self._level = 0.0

    def reset(self) -> None:
        self._level = 0.0

    def act(self, obs: Observation, truth) -> BrakeCommand:
        c = self.cfg
        crit = truth.critical
        if crit is None or crit.ttc_s == float("inf"):
            self._level = 0.0
            return BrakeCommand()
        ttc, gap, v_rel = crit.ttc_s, max(crit.gap_m, 0.01), crit.closing_speed_mps
        demand = 0.0
        if ttc <= c.full_ttc_s:
            demand = c.full_decel_mps2
        elif ttc <= c.partial_ttc_s:
            required = v_rel**2 / (2 * gap)
            demand = c.full_decel_mps2 if required > c.required_decel_margin * c.partial_decel_mps2 else c.partial_decel_mps2
        self._level = max(self._level, demand)
        return BrakeCommand(decel_mps2=self._level, warning=ttc <= c.warn_ttc_s or self._level > 0)
