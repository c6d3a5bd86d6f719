"""Closed-loop run of one scenario case with one controller; writes its outputs.

Per frame: capture -> ground truth -> controller -> the command is queued and takes
effect ``compute_latency_s`` after the frame's capture time -> traffic integrates to
the next frame. The first warning / brake are logged at the traffic step in which
they take effect, with the exact TTC of the critical actor at that step.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import time
from dataclasses import asdict
from pathlib import Path

import cv2
import numpy as np
import yaml

from bittc_core.atomic import write_text_atomic
from controllers.base import BrakeCommand, Controller, Observation
from scenarios.spec import ScenarioCase
from sim.camera import CameraConfig
from sim.episode import ScenarioSim
from sim.textures import TextureStyle
from sim.traffic import ActuatorConfig
from sim.video import VideoWriter, hud, ttc_overlay

SUMMARY_KEYS = (
    "scenario", "family", "controller", "seed", "threat", "collision", "impact_speed_kph",
    "relative_impact_speed_kph", "speed_reduction_kph", "min_gap_m", "t_first_warning_s",
    "ttc_at_first_warning_s", "t_first_brake_s", "ttc_at_first_brake_s", "false_alarm",
    "end_reason", "steps", "sim_time_s", "wall_time_s",
)  # fmt: skip


def _r(x: float | None, nd: int = 4) -> float | None:
    if x is None or not math.isfinite(x):
        return None
    return round(float(x), nd)


class _CommandQueue:
    """Commands in the order they take effect; the latest one in effect wins."""

    def __init__(self) -> None:
        self._pending: list[tuple[float, BrakeCommand]] = []
        self.active = BrakeCommand()

    def push(self, t_effect_s: float, cmd: BrakeCommand) -> None:
        self._pending.append((t_effect_s, cmd))

    def update(self, t_s: float) -> bool:
        """Make due commands active; True when the active command changed."""
        changed = False
        while self._pending and self._pending[0][0] <= t_s + 1e-9:
            self.active = self._pending.pop(0)[1]
            changed = True
        return changed


def run_case(
    case: ScenarioCase,
    controller: Controller,
    camera: CameraConfig,
    seed: int,
    out_dir: Path | None = None,
    video: bool = False,
    actuator: ActuatorConfig | None = None,
    textures: TextureStyle = TextureStyle(),
) -> dict:
    """Run ``case`` closed loop; returns the summary. With ``out_dir`` writes
    summary.json, trace.csv, config.yaml (and camera.mp4 with ``video``)."""
    wall0 = time.perf_counter()
    render = controller.needs_camera or video
    sim = ScenarioSim(case, camera, seed, render=render, actuator=actuator, textures=textures)
    writer = VideoWriter(out_dir / "camera.mp4", camera.fps_hz) if (video and out_dir is not None) else None
    try:
        controller.reset()
        truth = sim.reset()
        queue = _CommandQueue()
        first_warn = first_brake = None  # (t_s, ttc_s)
        rows: list[dict] = []
        prev = None
        frame = sim.capture() if render else None
        steps = 0
        end_reason = None
        while True:
            if frame is not None and prev is not None:
                truth.gt = sim.ground_truth(prev, frame)
            obs = Observation(sim.t_s, float(sim.ego.speed), frame.image if frame is not None else None,
                              prev.image if prev is not None else None, camera.dt_s)  # fmt: skip
            cmd = controller.act(obs, truth if controller.uses_ground_truth else None)
            if not (math.isfinite(cmd.decel_mps2) and cmd.decel_mps2 >= 0):
                raise ValueError(f"controller {controller.name!r} returned decel_mps2 = {cmd.decel_mps2}")
            queue.push(sim.t_s + max(cmd.compute_latency_s, 0.0), cmd)
            for k in range(sim.n_sub):
                if queue.update(sim.t_s):
                    a = queue.active
                    if a.warning and first_warn is None:
                        first_warn = (sim.t_s, _crit_ttc(sim))
                    if a.decel_mps2 > 0 and first_brake is None:
                        first_brake = (sim.t_s, _crit_ttc(sim))
                if k == 0:  # the row shows the command in effect at the frame's capture time
                    rows.append(_trace_row(sim, truth, queue.active, cmd))
                    if writer is not None and frame is not None:
                        writer.write(_video_frame(frame.image, truth, queue.active, sim, writer.scale_for(camera.width_px)))
                sim.substep(queue.active.decel_mps2)
            steps += 1
            truth = sim.truth()
            end_reason = sim.done(truth)
            if end_reason:
                break
            if render:
                prev, frame = frame, sim.capture()
        col = sim.collision
        any_alert = first_warn is not None or first_brake is not None
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
            "false_alarm": (not case.threat) and any_alert,
            "end_reason": end_reason,
            "steps": steps,
            "sim_time_s": _r(sim.t_s),
            "wall_time_s": round(time.perf_counter() - wall0, 3),
        }
        if out_dir is not None:
            _write_outputs(out_dir, case, controller, camera, seed, sim.actuator, summary, rows, video, textures)
            if writer is not None:
                writer.close()
        return summary
    except BaseException:
        if writer is not None:
            writer.abort()
        raise
    finally:
        sim.close()


def _crit_ttc(sim: ScenarioSim) -> float | None:
    c = sim.truth().critical
    return c.ttc_s if c is not None and math.isfinite(c.ttc_s) else None


def _trace_row(sim: ScenarioSim, truth, active: BrakeCommand, decided: BrakeCommand) -> dict:
    row = {
        "t_s": f"{sim.t_s:.3f}",
        "ego_speed_kph": f"{sim.ego.speed * 3.6:.4f}",
        "ego_accel_mps2": f"{sim.ego.current_accel_mps2:.4f}",
        "critical_actor": truth.critical.instance if truth.critical else "",
        "critical_ttc_s": f"{truth.critical.ttc_s:.4f}" if truth.critical and math.isfinite(truth.critical.ttc_s) else "",
        "warning": int(active.warning),
        "brake_cmd_mps2": f"{active.decel_mps2:.3f}",
        "decided_brake_mps2": f"{decided.decel_mps2:.3f}",
        "compute_latency_ms": f"{decided.compute_latency_s * 1e3:.2f}",
    }
    for a in truth.actors:
        row[f"gap_m_actor{a.instance}"] = f"{a.gap_m:.4f}"
    return row


def _video_frame(image: np.ndarray, truth, active: BrakeCommand, sim: ScenarioSim, scale: int) -> np.ndarray:
    img = image
    if truth.gt is not None:
        img = ttc_overlay(image, truth.gt.tau_s, truth.gt.valid, truth.gt.instance)
    img = cv2.resize(img, (img.shape[1] * scale, img.shape[0] * scale), interpolation=cv2.INTER_NEAREST)
    crit = truth.critical
    ttc = f"{crit.ttc_s:.2f} s" if crit and math.isfinite(crit.ttc_s) else "inf"
    gap = f"{crit.gap_m:.1f} m" if crit else "-"
    lines = [
        f"t {sim.t_s:5.2f} s   speed {sim.ego.speed * 3.6:5.1f} km/h",
        f"gap {gap}   TTC {ttc}",
        f"brake {active.decel_mps2:.1f} m/s2" + ("   WARNING" if active.warning else ""),
    ]
    return hud(img, lines, active.warning or active.decel_mps2 > 0)


def _write_outputs(out_dir: Path, case, controller, camera, seed, actuator, summary, rows, video, textures) -> None:
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
    config = {
        "scenario": case.to_dict(),
        "controller": controller.name,
        "seed": seed,
        "camera": asdict(camera),
        "textures": asdict(textures),
        "actuator": asdict(actuator),
        "video": video,
    }
    write_text_atomic(out_dir / "trace.csv", buf.getvalue())
    write_text_atomic(out_dir / "config.yaml", yaml.safe_dump(config, sort_keys=False))
    write_text_atomic(out_dir / "summary.json", json.dumps(summary, indent=2) + "\n")
