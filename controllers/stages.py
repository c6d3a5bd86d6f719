"""Staged, latched AEB output shared by the oracle and the geofence controllers.

Stages, as production AEB systems stage them (Euro NCAP / UN R152 style), on the
bumper-to-bumper TTC of the critical in-path actor:
  1. forward-collision warning when TTC <= ``warn_ttc_s`` (2.4 s, above NHTSA's
     2.1 s minimum for a stopped lead at 72 km/h);
  2. partial braking at ``partial_decel_mps2`` when TTC <= ``partial_ttc_s`` (1.6 s),
     full braking instead when the constant deceleration needed to stop the closing
     (v_rel^2 / (2 gap) = v_rel / (2 TTC)) exceeds ``required_decel_margin`` times the
     partial deceleration;
  3. full braking when TTC <= ``full_ttc_s`` (0.9 s).
Braking latches: once engaged it is never reduced while a threat remains, and it is
released (with the warning) only when the controller says the threat is gone.

``fence_stages`` maps a geofence controller's quantized TTC (the smallest fired fence) to
these stages.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from controllers.base import BrakeCommand

MAX_DECEL_MPS2 = 9.0  # [m/s^2] full braking on dry asphalt


@dataclass(frozen=True)
class StageConfig:
    warn_ttc_s: float = 2.4  # [s] bumper-to-bumper TTC
    partial_ttc_s: float = 1.6  # [s]
    full_ttc_s: float = 0.9  # [s]
    partial_decel_mps2: float = 4.0  # [m/s^2]
    full_decel_mps2: float = MAX_DECEL_MPS2  # [m/s^2]
    required_decel_margin: float = 0.8  # [-] full braking when v_rel/(2 TTC) > margin * partial decel

    def __post_init__(self) -> None:
        if not 0 < self.full_ttc_s <= self.partial_ttc_s <= self.warn_ttc_s:
            raise ValueError(f"StageConfig needs 0 < full_ttc_s <= partial_ttc_s <= warn_ttc_s, got {self}")
        if not 0 < self.partial_decel_mps2 <= self.full_decel_mps2 <= MAX_DECEL_MPS2:
            raise ValueError(f"StageConfig needs 0 < partial <= full decel <= {MAX_DECEL_MPS2} m/s^2, got {self}")


class StagedBrake:
    """Latched stage logic: ``update`` with which stages a threat has reached."""

    def __init__(self, cfg: StageConfig) -> None:
        self.cfg = cfg
        self.level_mps2 = 0.0

    def reset(self) -> None:
        self.level_mps2 = 0.0

    def update(self, warn: bool, partial: bool, full: bool, required_decel_mps2: float) -> BrakeCommand:
        """A threat is present; ``warn`` / ``partial`` / ``full``: its stage thresholds reached."""
        c = self.cfg
        demand = 0.0
        if full:
            demand = c.full_decel_mps2
        elif partial:
            demand = (
                c.full_decel_mps2
                if required_decel_mps2 > c.required_decel_margin * c.partial_decel_mps2
                else c.partial_decel_mps2
            )
        self.level_mps2 = max(self.level_mps2, demand)
        return BrakeCommand(decel_mps2=self.level_mps2, warning=warn or self.level_mps2 > 0)

    def release(self) -> BrakeCommand:
        """No threat any more: brakes and warning off."""
        self.level_mps2 = 0.0
        return BrakeCommand()


def nearest_log(values: np.ndarray, target: float) -> int:
    """Index of the value nearest to ``target`` in log scale (ties: the smaller value)."""
    d = np.abs(np.log(values) - math.log(max(target, 1e-9)))
    return int(np.flatnonzero(d == d.min())[0])


def fence_stages(
    thr: np.ndarray, tau_hat_s: float, speed_mps: float, bumper_ahead_m: float, cfg: StageConfig
) -> tuple[list[bool], float]:
    """The stages (warn, partial, full) that quantized TTC ``tau_hat_s`` [s, camera plane]
    reaches among sorted fences ``thr`` [s], and the deceleration [m/s^2] a static obstacle
    asks. A stage threshold T [s, bumper to bumper] becomes the camera-plane T + d / s (the
    bumper lies d ahead of the camera; a static obstacle covers d in d / s) and is assigned
    the fence nearest to that in log tau; it is reached when tau_hat <= that fence. The
    required deceleration of a static obstacle: s / (2 (tau_hat - d / s))."""
    offset_s = bumper_ahead_m / speed_mps
    reached = [
        tau_hat_s <= thr[nearest_log(thr, T + offset_s)] + 1e-9
        for T in (cfg.warn_ttc_s, cfg.partial_ttc_s, cfg.full_ttc_s)
    ]
    return reached, speed_mps / (2 * max(tau_hat_s - offset_s, 0.05))


def fired_fences(sizes: np.ndarray, streak: np.ndarray, cfg) -> tuple[np.ndarray, np.ndarray]:
    """In-path region sizes [px] of a view's fences (from the smallest up) and their streaks
    of consecutive jobs -> (which fences fire, the new streaks): a fence hits with a region
    of ``cfg.min_region_px``; with ``cfg.nested`` only where a larger fence hits too (what
    lies inside tau_i lies inside every larger fence); it fires after
    ``cfg.persistence_frames`` hits in a row."""
    hits = sizes >= cfg.min_region_px
    if cfg.nested:
        hits &= np.append(np.logical_or.accumulate(hits[::-1])[::-1][1:], True)
    streak = np.where(hits, streak + 1, 0)
    return streak >= cfg.persistence_frames, streak
