"""Run several scenario cases with one controller and tabulate their outcomes."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

from bittc_core.atomic import write_text_atomic
from controllers.base import Controller
from scenarios.spec import ScenarioCase
from sim.camera import CameraConfig
from sim.latency import LatencyMode
from sim.ncap_score import format_family_rows, impact_share, points
from sim.runner import SUMMARY_KEYS, TABLE_CAMERA_KEYS, run_case
from sim.text_table import text_table
from sim.textures import TextureStyle

TABLE_COLUMNS = (
    ("scenario", 28),
    ("threat", 6),
    ("collision", 9),
    ("impact_speed_kph", 8),
    ("min_gap_m", 8),
    ("ttc_at_first_seen_s", 8),
    ("ttc_at_first_warning_s", 8),
    ("ttc_at_first_brake_s", 8),
    ("false_alarm", 5),
    ("latency_ms_mean", 7),
    ("latency_ms_p95", 7),
    ("lag", 18),
)
HEADERS = {
    "impact_speed_kph": "impact",
    "min_gap_m": "gap_m",
    "ttc_at_first_seen_s": "ttc_seen",
    "ttc_at_first_warning_s": "ttc_warn",
    "ttc_at_first_brake_s": "ttc_brk",
    "false_alarm": "FA",
    "latency_ms_mean": "lat_ms",
    "latency_ms_p95": "p95_ms",
    "lag": "fence lag [s]",
}


def run_cases(
    cases: list[ScenarioCase],
    controller: Controller,
    camera: CameraConfig,
    seed: int,
    out_dir: Path,
    video: bool = False,
    progress: bool = True,
    textures: TextureStyle = TextureStyle(),
    latency: LatencyMode | None = None,
    sensor=None,
) -> list[dict]:
    """Run every case into ``out_dir/<case>/`` with the one ``controller`` (reset per run)
    and write ``out_dir/summary.{csv,json}``; ``sensor``: as ``run_case``'s."""
    summaries = []
    it = cases
    if progress and len(cases) > 1:
        from tqdm import tqdm

        it = tqdm(cases, desc=controller.name, unit="run", leave=False)
    for case in it:
        summaries.append(
            run_case(
                case,
                controller,
                camera,
                seed,
                out_dir / case.name,
                video=video,
                textures=textures,
                latency=latency,
                sensor=sensor,
            )
        )
    write_table(out_dir, summaries)
    return summaries


def _csv_value(v):
    if v is None:
        return ""
    if isinstance(v, (list, tuple)):
        return " ".join(f"{x:g}" for x in v)
    if isinstance(v, dict):
        return " ".join(f"{k}:{'' if x is None else x}" for k, x in v.items())
    return v


def write_table(out_dir: Path, summaries: list[dict]) -> None:
    keys = list(SUMMARY_KEYS) + [k for k in TABLE_CAMERA_KEYS if any(k in s for s in summaries)]
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=keys, lineterminator="\n")
    w.writeheader()
    for s in summaries:
        w.writerow({k: _csv_value(s.get(k)) for k in keys})
    write_text_atomic(out_dir / "summary.csv", buf.getvalue())
    write_text_atomic(out_dir / "summary.json", json.dumps(summaries, indent=2) + "\n")


def _lag_cell(s: dict) -> str | None:
    lag = s.get("fence_lag_s")
    if not lag:
        return None
    return "/".join("-" if v is None else f"{v:.2f}" for v in lag.values())


def format_table(summaries: list[dict], markdown: bool = False) -> str:
    """One line per run and a totals line. ``fence lag``: per threshold, smallest first,
    the threshold minus the critical actor's exact camera-plane TTC when the fence first
    covered half of it ('-': never)."""

    def cell(s: dict, k: str) -> str:
        v = _lag_cell(s) if k == "lag" else s.get(k)
        if v is None:
            return "-"
        if isinstance(v, bool):
            return "yes" if v else "no"
        if isinstance(v, float):
            return f"{v:.2f}"
        return str(v)

    measured = {"lag": "fence_lag_s", "ttc_at_first_seen_s": "ttc_at_first_seen_s"}  # camera controllers only
    cols = [
        (k, n) for k, n in TABLE_COLUMNS if k not in measured or any(s.get(measured[k]) is not None for s in summaries)
    ]
    threats = [s for s in summaries if s["threat"]]
    benign = [s for s in summaries if not s["threat"]]
    avoided = sum(not s["collision"] for s in threats)
    fas = sum(s["false_alarm"] for s in benign)
    total = f"threats avoided: {avoided}/{len(threats)}   false alarms: {fas}/{len(benign)}"
    unavoidable = [s for s in threats if s.get("unavoidable")]
    if unavoidable:
        total += f"   unavoidable by braking: {len(unavoidable)} ({unavoidable[0]['unavoidable']}"
        total += f", {', '.join(s['scenario'] for s in unavoidable)})"
    if threats:
        total += ("\n\n" if markdown else "\n") + f"points: {sum(points(s) for s in threats):.1f}/{len(threats)}"
        share = impact_share(summaries)
        total += f"   mean impact of the rest: {share:.2f} of the test speed" if share is not None else ""
    if len({s["family"] for s in summaries}) > 1:
        total += "\n\n" + format_family_rows(summaries, markdown)
    if markdown:
        table = text_table(
            [HEADERS.get(k, k) for k, _ in cols], [[cell(s, k) for k, _ in cols] for s in summaries], True
        )
        return "\n".join([table, "", total])
    head = " ".join(f"{HEADERS.get(k, k):<{n}}" for k, n in cols)
    lines = [head, "-" * len(head)]
    lines += [" ".join(f"{cell(s, k):<{n}}" for k, n in cols) for s in summaries]
    return "\n".join(lines + ["-" * len(head), total])
