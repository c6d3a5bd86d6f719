"""Run several scenario cases and tabulate their outcomes."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import controllers
from bittc_core.atomic import write_text_atomic
from scenarios.spec import ScenarioCase
from sim.camera import CameraConfig
from sim.runner import SUMMARY_KEYS, run_case
from sim.textures import TextureStyle

TABLE_COLUMNS = (
    ("scenario", 28), ("threat", 6), ("collision", 9), ("impact_speed_kph", 8), ("min_gap_m", 8),
    ("ttc_at_first_warning_s", 8), ("ttc_at_first_brake_s", 8), ("false_alarm", 5),
)  # fmt: skip
HEADERS = {"impact_speed_kph": "impact", "min_gap_m": "gap_m", "ttc_at_first_warning_s": "ttc_warn",
           "ttc_at_first_brake_s": "ttc_brk", "false_alarm": "FA"}  # fmt: skip


def run_cases(cases: list[ScenarioCase], controller: str, camera: CameraConfig, seed: int, out_dir: Path,
              video: bool = False, progress: bool = True, textures: TextureStyle = TextureStyle()) -> list[dict]:  # fmt: skip
    """Run every case into ``out_dir/<case>/`` and write ``out_dir/summary.{csv,json}``."""
    summaries = []
    it = cases
    if progress and len(cases) > 1:
        from tqdm import tqdm

        it = tqdm(cases, desc=f"{controller}", unit="run", leave=False)
    for case in it:
        summaries.append(run_case(case, controllers.make(controller), camera, seed, out_dir / case.name, video=video,
                                  textures=textures))
    write_table(out_dir, summaries)
    return summaries


def write_table(out_dir: Path, summaries: list[dict]) -> None:
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(SUMMARY_KEYS), lineterminator="\n")
    w.writeheader()
    for s in summaries:
        w.writerow({k: ("" if s[k] is None else s[k]) for k in SUMMARY_KEYS})
    write_text_atomic(out_dir / "summary.csv", buf.getvalue())
    write_text_atomic(out_dir / "summary.json", json.dumps(summaries, indent=2) + "\n")


def format_table(summaries: list[dict]) -> str:
    def cell(v) -> str:
        if v is None:
            return "-"
        if isinstance(v, bool):
            return "yes" if v else "no"
        if isinstance(v, float):
            return f"{v:.2f}"
        return str(v)

    head = " ".join(f"{HEADERS.get(k, k):<{n}}" for k, n in TABLE_COLUMNS)
    lines = [head, "-" * len(head)]
    for s in summaries:
        lines.append(" ".join(f"{cell(s[k]):<{n}}" for k, n in TABLE_COLUMNS))
    threats = [s for s in summaries if s["threat"]]
    benign = [s for s in summaries if not s["threat"]]
    avoided = sum(not s["collision"] for s in threats)
    fas = sum(s["false_alarm"] for s in benign)
    lines.append("-" * len(head))
    lines.append(f"threats avoided: {avoided}/{len(threats)}   false alarms: {fas}/{len(benign)}")
    return "\n".join(lines)
