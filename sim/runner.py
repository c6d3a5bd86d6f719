"""Closed-loop run of one scenario case with one controller; writes its outputs.

The loop itself is ``sim.loop.ClosedLoop`` (latency, frame skipping, command queue,
end of run). The first warning / brake are logged at the traffic step in which they
take effect, with the exact bumper-to-bumper TTC of the critical actor at that step.
Per-pixel TTC (the estimator's, the fence lag's) is to the camera plane instead.
"""

from __future__ import annotations

import csv
import io
import json
import math
import time
from dataclasses import asdict, is_dataclass
from pathlib import Path

import cv2
import numpy as np
import yaml

from bittc_core.atomic import write_text_atomic
from controllers.base import Controller
from controllers.stages import MAX_DECEL_MPS2
from scenarios.spec import ScenarioCase
from sim.camera import CameraConfig
from sim.episode import ScenarioSim
from sim.fence_lag import FenceLagMeter
from sim.latency import LatencyMode, parse_latency
from sim.loop import ClosedLoop
from sim.textures import TextureStyle
from sim.traffic import ActuatorConfig
from sim.video import VideoWriter, hud, ttc_overlay

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
)
#: per threshold [s]: the critical actor's exact camera-plane TTC when the fence first covered half of it,
#: the fence's lag (threshold minus that TTC; the earlier cover of the views), the lag in each view, and
#: the persistent lag (from the first frame the fence holds to the end); see sim.fence_lag
LAG_KEYS = ("fence_cover_ttc_s", "fence_lag_s", "fence_lag_wide_s", "fence_lag_fovea_s", "fence_lag_persistent_s")


def _r(x: float | None, nd: int = 4) -> float | None:
    if x is None or not math.isfinite(x):
        return None
    return round(float(x), nd)


def run_case(
    case: ScenarioCase,
    controller: Controller,
    camera: CameraConfig,
    seed: int,
    out_dir: Path | None = None,
    video: bool = False,
    actuator: ActuatorConfig | None = None,
    textures: TextureStyle = TextureStyle(),
    latency: LatencyMode | None = None,
) -> dict:
    """Run ``case`` closed loop; returns the summary. With ``out_dir`` writes
    summary.json, trace.csv, config.yaml, timing.json (and camera.mp4 with ``video``).

    ``latency`` defaults to ``measured`` for controllers that need the camera and
    ``fixed:0`` for the others. With a fixed or profile latency, summary.json,
    trace.csv and config.yaml are the same bytes for the same seed; wall-clock figures
    go to timing.json."""
    wall0 = time.perf_counter()
    latency = latency or default_latency(controller)
    render = controller.needs_camera or video
    sim = ScenarioSim(case, camera, seed, render=render, actuator=actuator, textures=textures)
    writer = VideoWriter(out_dir / "camera.mp4", camera.fps_hz) if (video and out_dir is not None) else None
    lag = lag_meter_for(controller)
    hook = None
    if writer is not None:
        scale = writer.scale_for(camera.width_px)
        hook = lambda rec, frame: writer.write(_video_frame(frame, rec, loop, scale))  # noqa: E731
    loop = ClosedLoop(
        sim,
        latency,
        num_alphas=controller.num_alphas,
        pairs=controller.needs_camera,
        frame_stride=controller.frame_stride,
        on_capture=hook,
        lag_meter=lag,
    )
    try:
        loop.drive(controller)
        summary = summarize(case, controller, seed, loop, latency, lag)
        if out_dir is not None:
            timing = {
                "wall_time_s": round(time.perf_counter() - wall0, 3),
                **{k: round(v, 4) for k, v in sorted(loop.timing.items())},
            }
            _write_outputs(
                out_dir,
                case,
                controller,
                camera,
                seed,
                sim.actuator,
                summary,
                _trace_rows(loop),
                video,
                textures,
                latency,
                timing,
            )
            if writer is not None:
                writer.close()
        return summary
    except BaseException:
        if writer is not None:
            writer.abort()
        raise
    finally:
        sim.close()


def lag_meter_for(controller: Controller) -> FenceLagMeter | None:
    """A fence-lag meter counting inside as the controller does (its ``prob_inside``), for camera controllers."""
    if not controller.needs_camera:
        return None
    return FenceLagMeter(getattr(getattr(controller, "cfg", None), "prob_inside", 0.5))


def default_latency(controller: Controller) -> LatencyMode:
    """``measured`` for controllers that look at the camera, ``fixed:0`` otherwise."""
    return parse_latency("measured" if controller.needs_camera else "fixed:0")


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
    }
    if lag is not None:
        summary["fence_cover_ttc_s"] = lag.cover_ttc()
        summary["fence_lag_s"] = lag.lag_s()
        summary["fence_lag_wide_s"] = lag.lag_s("wide")
        summary["fence_lag_fovea_s"] = lag.lag_s("fovea") if sim.camera.fovea_zoom is not None else None
        summary["fence_lag_persistent_s"] = lag.persistent_lag_s()
    return summary


def _trace_rows(loop: ClosedLoop) -> list[dict]:
    rows = []
    for rec in loop.records:
        truth, active = rec.truth, rec.active
        crit = truth.critical
        row = {
            "t_s": f"{rec.t_s:.3f}",
            "ego_speed_kph": f"{rec.ego_speed_mps * 3.6:.4f}",
            "ego_accel_mps2": f"{rec.ego_accel_mps2:.4f}",
            "critical_actor": crit.instance if crit else "",
            "critical_ttc_s": f"{crit.ttc_s:.4f}" if crit and math.isfinite(crit.ttc_s) else "",
            "warning": int(active.warning),
            "brake_cmd_mps2": f"{active.decel_mps2:.3f}",
            "frame": rec.status,
            "latency_ms": f"{rec.latency_s * 1e3:.2f}" if rec.latency_s is not None else "",
            "wait_ms": f"{rec.wait_s * 1e3:.2f}" if rec.wait_s is not None else "",
            "decided_warning": int(rec.decided.warning) if rec.decided else "",
            "decided_brake_mps2": f"{rec.decided.decel_mps2:.3f}" if rec.decided else "",
        }
        for view, shares in rec.fence_cover.items():
            tag = "" if view == "wide" else f"{view}_"
            for k, v in shares.items():
                row[f"crit_inside_{tag}{k}s"] = f"{v:.3f}"
        if rec.decided is not None:
            for k, v in rec.decided.telemetry.items():
                if k != "estimator_ms" or not loop.latency.deterministic:
                    row[k] = v
        for a in truth.actors:
            row[f"gap_m_actor{a.instance}"] = f"{a.gap_m:.4f}"
        rows.append(row)
    return rows


def _view_image(frame, rec, loop: ClosedLoop, name: str, view) -> np.ndarray:
    """One view's frame with the controller's fences over it, or the exact TTC where it has none."""
    from sim.video import geofence_overlay

    img = frame.view(name)[0]
    if view is not None:
        return geofence_overlay(img, view)
    gt = loop.ground_truth(rec.index, name)
    return ttc_overlay(img, gt.tau_s, gt.valid, gt.instance) if gt is not None else img


def _video_frame(frame, rec, loop: ClosedLoop, scale: int) -> np.ndarray:
    """The wide view (fences or exact TTC over it) scaled up, the fovea as an inset in its
    lower right corner with its footprint outlined on the wide view, and the HUD."""
    from sim.video import fovea_inset

    active, truth = rec.active, rec.truth
    img = _view_image(frame, rec, loop, "wide", active.view)
    img = cv2.resize(img, (img.shape[1] * scale, img.shape[0] * scale), interpolation=cv2.INTER_NEAREST)
    if frame.fovea is not None:
        inset = _view_image(frame, rec, loop, "fovea", active.fovea_view)
        img = fovea_inset(img, inset, loop.sim.camera, scale)
    crit = truth.critical
    ttc = f"{crit.ttc_s:.2f} s" if crit and math.isfinite(crit.ttc_s) else "inf"
    gap = f"{crit.gap_m:.1f} m" if crit else "-"
    stage = (
        "FULL BRAKE"
        if active.decel_mps2 >= MAX_DECEL_MPS2 - 0.1
        else "BRAKE"
        if active.decel_mps2 > 0
        else "WARNING"
        if active.warning
        else "-"
    )
    last = next((r for r in reversed(loop.records) if r.latency_s is not None), None)
    lat = f"{last.latency_s * 1e3:.0f} ms" if last is not None else "-"
    alert = active.warning or active.decel_mps2 > 0
    # the view whose fence fired in the job behind the command in effect; a latched stage holds without one
    fired = active.telemetry.get("fired_view") or ("none (stage held)" if alert else "-")
    lines = [
        f"t {rec.t_s:5.2f} s   speed {rec.ego_speed_mps * 3.6:5.1f} km/h",
        f"gap {gap}   exact TTC {ttc}",
        f"{stage}  {active.decel_mps2:.1f} m/s2   latency {lat}",
    ]
    if frame.fovea is not None:
        lines.append(f"fired in view: {fired}")
    return hud(img, lines, alert)


def _write_outputs(
    out_dir: Path, case, controller, camera, seed, actuator, summary, rows, video, textures, latency, timing
) -> None:
    out_dir.mkdir(parents=True, exist_ok=True)
    buf = io.StringIO()
    fieldnames = list(rows[0].keys()) if rows else ["t_s"]
    for r in rows:
        for k in r:
            if k not in fieldnames:
                fieldnames.append(k)
    w = csv.DictWriter(buf, fieldnames=fieldnames, lineterminator="\n", restval="")
    w.writeheader()
    w.writerows(rows)
    cfg = getattr(controller, "cfg", None)
    config = {
        "scenario": case.to_dict(),
        "controller": controller.name,
        "controller_config": _plain(asdict(cfg)) if is_dataclass(cfg) else None,
        "latency": str(latency),
        "seed": seed,
        "camera": asdict(camera),
        "textures": asdict(textures),
        "actuator": asdict(actuator),
        "video": video,
    }
    write_text_atomic(out_dir / "trace.csv", buf.getvalue())
    write_text_atomic(out_dir / "config.yaml", yaml.safe_dump(config, sort_keys=False))
    write_text_atomic(out_dir / "timing.json", json.dumps(timing, indent=2) + "\n")
    write_text_atomic(out_dir / "summary.json", json.dumps(summary, indent=2) + "\n")


def _plain(x):
    """Tuples -> lists, for YAML."""
    if isinstance(x, dict):
        return {k: _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    return x
