"""``DIR/report.html``: one self-contained page (plots linked by relative paths, so the
folder can be moved or zipped): the settings and the command, the summary table, the
plots, and a table of every run linking its folder, summary and video."""

from __future__ import annotations

import html
from pathlib import Path

from bittc_core.atomic import write_text_atomic
from sim.sweep import ncap, tables
from sim.sweep.plots import config_label
from sim.sweep.tables import FAMILY_HEAD, family_summary

_CSS = """
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 1100px; color: #222; }
table { border-collapse: collapse; font-size: 13px; margin: 1em 0; }
th, td { border: 1px solid #ccc; padding: 3px 7px; text-align: right; }
th { background: #f2f2f2; } td.l, th.l { text-align: left; }
img { max-width: 100%; border: 1px solid #ddd; margin: 0.5em 0; }
code, pre { background: #f6f6f6; padding: 2px 4px; } pre { padding: 8px; overflow-x: auto; }
.band { display: inline-block; width: 0.9em; height: 0.9em; border-radius: 2px; vertical-align: middle; }
"""


def _esc(x) -> str:
    return html.escape("–" if x is None else str(x))


def _table(header: list[str], rows: list[list], left: int = 1) -> str:
    th = "".join(f'<th class="{"l" if i < left else ""}">{_esc(h)}</th>' for i, h in enumerate(header))
    body = "".join(
        "<tr>" + "".join(f'<td class="{"l" if i < left else ""}">{c}</td>' for i, c in enumerate(r)) + "</tr>"
        for r in rows
    )
    return f"<table><tr>{th}</tr>{body}</table>"


def _summary_table(summary: list[dict]) -> str:
    rows = [[_esc(c) for c in tables.summary_cells(s)] for s in summary]
    return _table(list(tables.SUMMARY_HEAD), rows, left=3)


def _runs_table(out_dir: Path, rows: list[dict]) -> str:
    header = [
        "run",
        "scenario",
        "configuration",
        "seed",
        "collision",
        "rel. impact [km/h]",
        "band",
        "TTC warn / brake [s]",
        "false alarm",
        "latency [ms]",
        "files",
    ]
    out = []
    for r in rows:
        if r["status"] != "ok":
            out.append(
                [
                    _esc(r["run_id"]),
                    _esc(r["scenario"]),
                    _esc(config_label(r)),
                    _esc(r["seed"]),
                    f"<b>failed</b>: {_esc(r['error'])}",
                    "",
                    "",
                    "",
                    "",
                    "",
                    "",
                ]
            )
            continue
        band = r["ncap_band"]
        swatch = f'<span class="band" style="background:{ncap.BAND_COLOURS[band]}"></span> {band}' if band else "–"
        links = [
            f'<a href="{_esc(r["folder"])}/">folder</a>',
            f'<a href="{_esc(r["folder"])}/summary.json">summary</a>',
            f'<a href="{_esc(r["folder"])}/trace.csv">trace</a>',
        ]
        if (out_dir / r["folder"] / "camera.mp4").is_file():
            links.append(f'<a href="{_esc(r["folder"])}/camera.mp4">video</a>')
        out.append(
            [
                _esc(r["run_id"]),
                _esc(r["scenario"]),
                _esc(config_label(r)),
                _esc(r["seed"]),
                "yes" if r["collision"] else "no",
                _esc(r["relative_impact_speed_kph"] or (0 if r["threat"] else None)),
                swatch,
                f"{_esc(r['ttc_at_first_warning_s'])} / {_esc(r['ttc_at_first_brake_s'])}",
                "yes" if r["false_alarm"] else "no",
                _esc(r["latency_ms_mean"]),
                " · ".join(links),
            ]
        )
    return _table(header, out, left=3)


def write_report(
    out_dir: Path,
    settings_json: str,
    command: str,
    summary: list[dict],
    rows: list[dict],
    plots: list[str],
    notes: list[str],
    videos: list[str],
) -> Path:
    """Write ``out_dir/report.html``; -> its path."""
    parts = [
        "<!doctype html><html><head><meta charset='utf-8'><title>bittc sweep</title>"
        f"<style>{_CSS}</style></head><body>",
        "<h1>bittc sweep</h1>",
        f"<p>Command: <code>{_esc(command)}</code></p>",
        "<details><summary>Settings (sweep.json)</summary>",
        f"<pre>{_esc(settings_json)}</pre></details>",
    ]
    parts += [f"<p>{_esc(n)}</p>" for n in notes]
    parts += [
        "<h2>Summary</h2>",
        "<p>Per controller, fovea, K and latency mode (definitions: <code>sim/sweep/tables.py</code>; "
        "Euro NCAP bands and gate: <code>sim/sweep/ncap.py</code>). Also as <a href='summary.csv'>summary.csv</a>, "
        "<a href='summary.md'>summary.md</a>; every run in <a href='results.csv'>results.csv</a>.</p>",
        _summary_table(summary),
        "<h2>Per family</h2>",
        "<p>Threats avoided, those that braking can avoid at all, false alarms, the mean impact speed of "
        "the collisions and Euro NCAP-style points from the impact speed (<code>sim/ncap_score.py</code>).</p>",
        _table(list(FAMILY_HEAD), [[_esc(x) for x in c] for c in family_summary(rows)], left=5),
        "<h2>Plots</h2>",
    ]
    parts += [f'<p><img src="plots/{_esc(p)}" alt="{_esc(p)}"></p>' for p in plots]
    for v in videos:
        parts.append(
            f'<p>Video: <a href="{_esc(v)}">{_esc(v)}</a></p><video src="{_esc(v)}" controls width="576"></video>'
        )
    parts += ["<h2>Runs</h2>", _runs_table(out_dir, rows), "</body></html>"]
    path = out_dir / "report.html"
    write_text_atomic(path, "\n".join(parts) + "\n")
    return path
