"""``results.csv`` (one row per run) and the per-configuration summary
(``summary.csv``, ``summary.md``: one row per controller x fovea x K x latency mode).

Definitions (threat runs are those of scenarios with ``threat: true``):
    threats avoided      threat runs without a collision / threat runs
    mean impact speed    over threat runs, an avoided run counting 0 km/h [km/h]
    mean speed reduction over threat runs [km/h]
    FCW pass             a threat run whose first warning came at an exact bumper TTC
                         >= 2.1 s (the NHTSA FCW criterion); the rate is over threat runs
    TTC at first warning mean and minimum over the threat runs that warned [s]
    false alarms         benign runs with any warning or brake / benign runs
    latency              the mean of the runs' mean latencies and of their p95 [ms]
    frames skipped       the share of captured frames the estimator skipped
    Euro NCAP bands, gate see ``sim.sweep.ncap``
"""

from __future__ import annotations

import csv
import io
import math

from bittc_core.atomic import write_text_atomic
from sim.ncap_score import FCW_TTC_S
from sim.runner import SUMMARY_KEYS, TABLE_CAMERA_KEYS
from sim.suite import _csv_value
from sim.sweep import ncap
from sim.text_table import text_table

RUN_KEYS = ("run_id", "status", "error", "config", "ego_speed_kph", "ncap_band", "folder")
RESULT_COLUMNS = RUN_KEYS + tuple(k for k in SUMMARY_KEYS if k not in RUN_KEYS) + TABLE_CAMERA_KEYS
SUMMARY_COLUMNS = (
    "controller",
    "fovea_zoom",
    "num_alphas",
    "latency_mode",
    "runs",
    "failed",
    "threats_avoided",
    "threats",
    "collisions",
    "mean_impact_speed_kph",
    "mean_speed_reduction_kph",
    "fcw_pass_rate",
    "ttc_first_warning_mean_s",
    "ttc_first_warning_min_s",
    "false_alarms",
    "benign_runs",
    "latency_ms_mean",
    "latency_ms_p95",
    "frames_skipped_share",
    "ncap_green",
    "ncap_yellow",
    "ncap_orange",
    "ncap_brown",
    "ncap_red",
    "ncap_ccrs_gate",
)


def result_row(spec, case, summary: dict | None, error: str | None) -> dict:
    row = {k: None for k in RESULT_COLUMNS}
    row.update(
        run_id=spec.run_id,
        config=spec.config_id,
        controller=spec.controller,
        num_alphas=spec.num_alphas,
        fovea_zoom=spec.fovea_zoom,
        latency_mode=spec.latency,
        seed=spec.seed,
        scenario=spec.case,
        family=case.family,
        threat=case.threat,
        ego_speed_kph=case.ego.speed_kph,
    )
    if summary is None:
        row.update(status="failed", error=(error or "").strip().splitlines()[-1] if error else "failed")
        return row
    row.update({k: summary.get(k) for k in RESULT_COLUMNS if k in summary})
    row.update(status="ok", error=None, folder=f"runs/{spec.run_id}", ncap_band=ncap.band_of_run(row))
    return row


def write_results(path, rows: list[dict]) -> None:
    write_text_atomic(path, _csv(RESULT_COLUMNS, rows))


def _csv(columns, rows) -> str:
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(columns), lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: _csv_value(r.get(k)) for k in columns})
    return buf.getvalue()


def _mean(xs):
    xs = [x for x in xs if x is not None and math.isfinite(x)]
    return round(sum(xs) / len(xs), 3) if xs else None


def summarize(rows: list[dict]) -> list[dict]:
    """One row per configuration, in the order the configurations first appear."""
    groups: dict[tuple, list[dict]] = {}
    for r in rows:
        groups.setdefault((r["controller"], r["fovea_zoom"], r["num_alphas"], r["latency_mode"]), []).append(r)
    out = []
    for (controller, zoom, k, latency), rs in groups.items():
        ok = [r for r in rs if r["status"] == "ok"]
        threats = [r for r in ok if r["threat"]]
        benign = [r for r in ok if not r["threat"]]
        warned = [r["ttc_at_first_warning_s"] for r in threats if r["ttc_at_first_warning_s"] is not None]
        frames = sum((r["frames_processed"] or 0) + (r["frames_skipped"] or 0) for r in ok)
        bands = [r["ncap_band"] for r in threats if r["ncap_band"]]
        s = {
            "controller": controller,
            "fovea_zoom": zoom,
            "num_alphas": k,
            "latency_mode": latency,
            "runs": len(rs),
            "failed": len(rs) - len(ok),
            "threats_avoided": sum(not r["collision"] for r in threats),
            "threats": len(threats),
            "collisions": sum(bool(r["collision"]) for r in threats),
            "mean_impact_speed_kph": _mean([r["impact_speed_kph"] or 0.0 for r in threats]),
            "mean_speed_reduction_kph": _mean([r["speed_reduction_kph"] for r in threats]),
            "fcw_pass_rate": round(sum(t >= FCW_TTC_S for t in warned) / len(threats), 3) if threats else None,
            "ttc_first_warning_mean_s": _mean(warned),
            "ttc_first_warning_min_s": min(warned) if warned else None,
            "false_alarms": sum(bool(r["false_alarm"]) for r in benign),
            "benign_runs": len(benign),
            "latency_ms_mean": _mean([r["latency_ms_mean"] for r in ok]),
            "latency_ms_p95": _mean([r["latency_ms_p95"] for r in ok]),
            "frames_skipped_share": round(sum(r["frames_skipped"] or 0 for r in ok) / frames, 4) if frames else None,
            **{f"ncap_{b}": bands.count(b) for b in ncap.BANDS},
            "ncap_ccrs_gate": ncap.ccrs_gate(threats),
        }
        out.append(s)
    return out


def write_summary(out_dir, summary: list[dict], rows: list[dict] | None = None) -> str:
    """summary.csv and summary.md (with ``rows``, the per-family table below it); -> the Markdown."""
    write_text_atomic(out_dir / "summary.csv", _csv(SUMMARY_COLUMNS, summary))
    md = markdown_table(summary)
    if rows:
        md += "\n\n" + family_markdown(rows)
    write_text_atomic(out_dir / "summary.md", md + "\n")
    return md


FAMILY_HEAD = ("controller", "fovea", "K", "latency", "family", "avoided", "avoidable", "false alarms", "impact [km/h]")
FAMILY_HEAD += ("points",)


def family_summary(rows: list[dict]) -> list[tuple[str, ...]]:
    """Per configuration and scenario family (``sim.ncap_score.family_rows``), as cells of ``FAMILY_HEAD``."""
    from sim.ncap_score import family_rows

    groups: dict[tuple, list[dict]] = {}
    for r in rows:
        if r["status"] == "ok":
            groups.setdefault((r["controller"], r["fovea_zoom"], r["num_alphas"], r["latency_mode"]), []).append(r)
    out = []
    for (controller, zoom, k, latency), rs in groups.items():
        for f in family_rows(rs):
            out.append(
                (
                    str(controller),
                    fovea_label(zoom),
                    str(k or "–"),
                    str(latency),
                    f["family"],
                    f"{f['avoided']}/{f['threats']}" if f["threats"] else "–",
                    str(f["avoidable"]) if f["threats"] else "–",
                    f"{f['false_alarms']}/{f['benign']}" if f["benign"] else "–",
                    _fmt(f["mean_impact_kph"], 1),
                    "–" if f["points"] is None else f"{f['points']:.2f}/{f['threats']}",
                )
            )
    return out


def family_markdown(rows: list[dict]) -> str:
    return text_table(FAMILY_HEAD, family_summary(rows), markdown=True)


def _fmt(v, nd=2) -> str:
    if v is None:
        return "–"
    if isinstance(v, float):
        return f"{v:.{nd}f}"
    return str(v)


SUMMARY_HEAD = (
    "controller",
    "fovea",
    "K",
    "latency",
    "avoided",
    "mean impact [km/h]",
    "FCW ≥ 2.1 s",
    "TTC at warning mean / min [s]",
    "false alarms",
    "latency mean / p95 [ms]",
    "skipped",
    "Euro NCAP G/Y/O/B/R",
    "CCRs ≤ 20 gate",
)


def fovea_label(zoom) -> str:
    """None -> 'off', 4.0 -> 'x4'."""
    return "off" if zoom is None or zoom == "" else f"x{float(zoom):g}"


def summary_cells(s: dict) -> tuple[str, ...]:
    """One summary row as the cells of ``SUMMARY_HEAD`` (text)."""
    avoided = f"{s['threats_avoided']}/{s['threats']}" + (f" ({s['failed']} failed)" if s["failed"] else "")
    return (
        str(s["controller"]),
        fovea_label(s["fovea_zoom"]),
        str(s["num_alphas"] or "–"),
        str(s["latency_mode"]),
        avoided,
        _fmt(s["mean_impact_speed_kph"], 1),
        "–" if s["fcw_pass_rate"] is None else f"{s['fcw_pass_rate']:.0%}",
        f"{_fmt(s['ttc_first_warning_mean_s'])} / {_fmt(s['ttc_first_warning_min_s'])}",
        f"{s['false_alarms']}/{s['benign_runs']}",
        f"{_fmt(s['latency_ms_mean'], 1)} / {_fmt(s['latency_ms_p95'], 1)}",
        "–" if s["frames_skipped_share"] is None else f"{s['frames_skipped_share']:.0%}",
        "/".join(str(s[f"ncap_{b}"]) for b in ncap.BANDS),
        {True: "pass", False: "fail", None: "–"}[s["ncap_ccrs_gate"]],
    )


def markdown_table(summary: list[dict]) -> str:
    return text_table(SUMMARY_HEAD, [summary_cells(s) for s in summary], markdown=True)
