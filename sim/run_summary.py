"""The summary of one closed-loop run (summary.json): its keys and how each is measured.

The first warning / brake are logged at the traffic step in which they take effect, with
the exact bumper-to-bumper TTC of the critical actor at that step. The fence-lag keys are
to the camera plane instead.
"""

from __future__ import annotations

import math

import numpy as np

from controllers.base import Controller
from scenarios.spec import ScenarioCase
from sim.fence_lag import FenceLagMeter
from sim.latency import LatencyMode
from sim.loop import ClosedLoop
from sim.ncap_score import points, unavoidable_reason

SUMMARY_KEYS = (
    "scenario",
    "family",
    "controller",
    "seed",
    "threat",
    "collision",
    "impact_speed_kph",
    "relative_impact_speed_kph",
    "speed_reduction_kph",
    "min_gap_m",
    "t_first_warning_s",
    "ttc_at_first_warning_s",
    "t_first_brake_s",
    "ttc_at_first_brake_s",
    "false_alarm",
    "end_reason",
    "steps",
    "sim_time_s",
    "num_alphas",
    "thresholds_s",
    "fovea_zoom",
    "latency_mode",
    "latency_ms_mean",
    "latency_ms_p95",
    "wait_ms_mean",
    "actuator_delay_ms",
    "frames_processed",
    "frames_skipped",
    "test_speed_kph",
    "unavoidable",
    "points",
)
#: the camera controllers' keys that a suite's summary.csv and a sweep's results.csv carry
TABLE_CAMERA_KEYS = ("fence_lag_s", "ttc_at_first_seen_s")
#: per threshold [s]: the critical actor's exact camera-plane TTC when the fence first covered half of it,
#: the fence's lag (threshold minus that TTC; the earlier cover of the views), the lag in each view, and
#: the persistent lag (from the first frame the fence holds to the end); and the critical actor's
#: bumper-to-bumper TTC when the camera first saw it; see sim.fence_lag
LAG_KEYS = (
    "fence_cover_ttc_s",
    "fence_lag_s",
    "fence_lag_wide_s",
    "fence_lag_fovea_s",
    "fence_lag_persistent_s",
    "ttc_at_first_seen_s",
)


def _r(x: float | None, nd: int = 4) -> float | None:
    if x is None or not math.isfinite(x):
        return None
    return round(float(x), nd)


def summarize(
    case: ScenarioCase,
    controller: Controller,
    seed: int,
    loop: ClosedLoop,
    latency: LatencyMode,
    lag: FenceLagMeter | None,
) -> dict:
    sim = loop.sim
    col = sim.collision
    first_warn, first_brake = loop.first_warning, loop.first_brake
    jobs = loop.processed
    lat_ms = np.array([r.latency_s for r in jobs], dtype=np.float64) * 1e3
    wait_ms = np.array([r.wait_s for r in jobs], dtype=np.float64) * 1e3
    thresholds = getattr(getattr(controller, "cfg", None), "thresholds_s", None)
    summary = {
        "scenario": case.name,
        "family": case.family,
        "controller": controller.name,
        "seed": seed,
        "threat": case.threat,
        "collision": col is not None,
        "impact_speed_kph": _r(col.impact_speed_mps * 3.6) if col else None,
        "relative_impact_speed_kph": _r(col.relative_impact_speed_mps * 3.6) if col else None,
        "speed_reduction_kph": _r(case.ego.speed_kph - (col.impact_speed_mps * 3.6 if col else sim.ego.speed * 3.6)),
        "min_gap_m": _r(sim.min_gap_m),
        "t_first_warning_s": _r(first_warn[0]) if first_warn else None,
        "ttc_at_first_warning_s": _r(first_warn[1]) if first_warn else None,
        "t_first_brake_s": _r(first_brake[0]) if first_brake else None,
        "ttc_at_first_brake_s": _r(first_brake[1]) if first_brake else None,
        "false_alarm": (not case.threat) and (first_warn is not None or first_brake is not None),
        "end_reason": loop.end_reason,
        "steps": len(loop.records),
        "sim_time_s": _r(sim.t_s),
        "num_alphas": controller.num_alphas,
        "thresholds_s": list(thresholds) if thresholds is not None else [],
        "fovea_zoom": sim.camera.fovea_zoom,
        "latency_mode": str(latency),
        "latency_ms_mean": _r(float(lat_ms.mean()), 3) if lat_ms.size else None,
        "latency_ms_p95": _r(float(np.percentile(lat_ms, 95)), 3) if lat_ms.size else None,
        "wait_ms_mean": _r(float(wait_ms.mean()), 3) if wait_ms.size else None,
        "actuator_delay_ms": _r(sim.actuator.delay_s * 1e3, 3),
        "frames_processed": len(jobs),
        "frames_skipped": sum(r.status == "skipped" for r in loop.records),
        "test_speed_kph": case.ego.speed_kph,
        "unavoidable": unavoidable_reason(case),
    }
    summary["points"] = points(summary)
    if lag is not None:
        summary["fence_cover_ttc_s"] = lag.cover_ttc()
        summary["fence_lag_s"] = lag.lag_s()
        summary["fence_lag_wide_s"] = lag.lag_s("wide")
        summary["fence_lag_fovea_s"] = lag.lag_s("fovea") if sim.camera.fovea_zoom is not None else None
        summary["fence_lag_persistent_s"] = lag.persistent_lag_s()
        summary["ttc_at_first_seen_s"] = _r(lag.first_seen_ttc_s)
    return summary
