"""The files of one closed-loop run: trace.csv (one row per traffic step), config.yaml, timing.json
and summary.json, each written atomically."""

from __future__ import annotations

import csv
import io
import json
import math
from dataclasses import asdict, is_dataclass
from pathlib import Path

import yaml

from bittc_core.atomic import write_text_atomic
from sim.loop import ClosedLoop


def trace_rows(loop: ClosedLoop) -> list[dict]:
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


def write_outputs(
    out_dir: Path,
    case,
    controller,
    camera,
    seed,
    actuator,
    summary,
    rows,
    video,
    textures,
    latency,
    timing,
    sensor=None,
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
        "sensor": sensor.as_dict() if sensor is not None else None,  # --realism's draw
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
