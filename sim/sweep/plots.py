"""The sweep's PNG plots (matplotlib, Agg backend; no display needed).

``latency_vs_k.png``      estimator latency (mean, p95 dotted) against K, per controller
                          and latency mode, with the frame interval above which frames
                          are skipped;
``warning_ttc_vs_k.png``  mean exact bumper TTC at the first warning of threat runs
                          against K, with NHTSA's 2.1 s;
``rates_vs_k.png``        threats avoided and false alarms (shares) against K;
``impact_vs_speed.png``   relative impact speed against ego speed of each threat run,
                          over Euro NCAP's colour bands (``sim.sweep.ncap``);
``timeline.png``          one case: ego speed, exact TTC and brake command against time,
                          one line per configuration (seed 0);
``rates_vs_latency.png``  threats avoided and FCW pass rate against the mean latency per
                          frame, one line per controller x fovea x latency mode, one point
                          per K: spend the compute on thresholds or on a fovea?
Controllers without thresholds (K = 0) are drawn as horizontal lines in the K plots.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

from sim.ncap_score import FCW_TTC_S
from sim.sweep import ncap

PLOTS = (
    "latency_vs_k.png",
    "warning_ttc_vs_k.png",
    "rates_vs_k.png",
    "impact_vs_speed.png",
    "timeline.png",
    "rates_vs_latency.png",
)
DPI = 110


def _legend(ax, **kw) -> None:
    """A legend only where something is labelled (an empty one warns)."""
    if ax.get_legend_handles_labels()[0]:
        ax.legend(**kw)


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(fig, path: Path) -> None:
    import os

    from bittc_core.atomic import open_temp_beside

    fd, tmp = open_temp_beside(path)
    try:
        with os.fdopen(fd, "wb") as f:
            fig.savefig(f, format="png", dpi=DPI, bbox_inches="tight", metadata={"Software": None})
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    finally:
        _plt().close(fig)


def _fovea(row: dict) -> str:
    z = row.get("fovea_zoom")
    return "" if z is None or z == "" else f" fovea x{float(z):g}"


def _by_config(summary: list[dict]):
    """(controller [+ fovea], latency) -> [(K, row)] sorted by K."""
    out: dict[tuple, list] = {}
    for s in summary:
        out.setdefault((s["controller"] + _fovea(s), s["latency_mode"]), []).append((s["num_alphas"], s))
    return {k: sorted(v, key=lambda kv: kv[0]) for k, v in out.items()}


def config_label(row: dict) -> str:
    k = f" K={row['num_alphas']}" if row["num_alphas"] else ""
    return f"{row['controller']}{_fovea(row)}{k}, {row['latency_mode']}"


def _k_plot(ax, summary, value, label_fmt="{c}, {l}"):
    ks = sorted({s["num_alphas"] for s in summary if s["num_alphas"]}) or [1]
    for (c, lat), pts in _by_config(summary).items():
        xs = [k for k, s in pts if value(s) is not None]
        ys = [value(s) for k, s in pts if value(s) is not None]
        if not ys:
            continue
        if pts[0][0] == 0:  # no thresholds: one value for every K
            ax.plot([ks[0], ks[-1]], [ys[0], ys[0]], "--", label=label_fmt.format(c=c, l=lat))
        else:
            ax.plot(xs, ys, "o-", label=label_fmt.format(c=c, l=lat))
    ax.set_xscale("log", base=2)
    ax.set_xticks(ks, [str(k) for k in ks])
    ax.set_xlabel("K (thresholds per frame)")
    ax.grid(alpha=0.3)


def plot_all(
    out_dir: Path, rows: list[dict], summary: list[dict], frame_dt_s: float, timeline_case: str | None
) -> list[str]:
    """Write the plots into ``out_dir/plots/``; -> their file names."""
    plt = _plt()
    d = out_dir / "plots"
    d.mkdir(exist_ok=True)
    est = [s for s in summary if s["num_alphas"]]

    fig, ax = plt.subplots(figsize=(6.4, 4))
    _k_plot(ax, est, lambda s: s["latency_ms_mean"])
    for pts in _by_config(est).values():
        ax.plot([k for k, _ in pts], [s["latency_ms_p95"] for _, s in pts], ":", color="gray", lw=0.8)
    ax.axhline(frame_dt_s * 1e3, color="k", lw=0.8)
    ax.text(1, frame_dt_s * 1e3, " frame interval: above it frames are skipped", va="bottom", fontsize=8)
    ax.set_ylabel("latency per frame [ms] (dotted: p95)")
    _legend(ax, fontsize=7)
    _save(fig, d / PLOTS[0])

    fig, ax = plt.subplots(figsize=(6.4, 4))
    _k_plot(ax, summary, lambda s: s["ttc_first_warning_mean_s"])
    ax.axhline(FCW_TTC_S, color="k", lw=0.8)
    ax.text(1, FCW_TTC_S, " NHTSA FCW: 2.1 s", va="bottom", fontsize=8)
    ax.set_ylabel("exact TTC at first warning, mean [s]")
    _legend(ax, fontsize=7)
    _save(fig, d / PLOTS[1])

    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
    _k_plot(a1, summary, lambda s: s["threats_avoided"] / s["threats"] if s["threats"] else None)
    a1.set_ylabel("threats avoided (share)")
    a1.set_ylim(-0.02, 1.02)
    _k_plot(a2, summary, lambda s: s["false_alarms"] / s["benign_runs"] if s["benign_runs"] else None)
    a2.set_ylabel("benign runs with a false alarm (share)")
    a2.set_ylim(-0.02, 1.02)
    _legend(a1, fontsize=7)
    _save(fig, d / PLOTS[2])

    _impact_plot(plt, d / PLOTS[3], rows)
    _timeline_plot(plt, d / PLOTS[4], out_dir, rows, timeline_case)
    _latency_rates_plot(plt, d / PLOTS[5], est, frame_dt_s)
    return list(PLOTS)


def _latency_rates_plot(plt, path: Path, est: list[dict], frame_dt_s: float) -> None:
    """Threats avoided and FCW pass rate against the mean latency per frame; a line per
    controller x fovea x latency mode through its K values (each point labelled K)."""
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
    for (c, lat), pts in _by_config(est).items():
        pts = [(k, s) for k, s in pts if s["latency_ms_mean"] is not None and s["threats"]]
        if not pts:
            continue
        xs = [s["latency_ms_mean"] for _, s in pts]
        for ax, value in ((a1, lambda s: s["threats_avoided"] / s["threats"]), (a2, lambda s: s["fcw_pass_rate"])):
            ys = [value(s) for _, s in pts]
            ax.plot(xs, ys, "o-", label=f"{c}, {lat}")
            for x, y, (k, _) in zip(xs, ys, pts):
                ax.annotate(f"K{k}", (x, y), textcoords="offset points", xytext=(3, 3), fontsize=7)
    for ax, label in ((a1, "threats avoided (share)"), (a2, f"FCW pass rate (first warning at TTC >= {FCW_TTC_S} s)")):
        ax.axvline(frame_dt_s * 1e3, color="k", lw=0.8)
        ax.set_xlabel("mean latency per frame [ms] (black: the frame interval)")
        ax.set_ylabel(label)
        ax.set_ylim(-0.02, 1.02)
        ax.grid(alpha=0.3)
    fig.suptitle("thresholds or a fovea: what the compute buys", fontsize=10)
    _legend(a1, fontsize=7)
    _save(fig, path)


def _impact_plot(plt, path: Path, rows: list[dict]) -> None:
    threats = [r for r in rows if r["status"] == "ok" and r["threat"]]
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    vmax = max([r["ego_speed_kph"] for r in threats] + [80.0])
    from matplotlib.patches import Rectangle

    for x0, x1, y0, y1, band in ncap.band_regions(vmax):
        ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, color=ncap.BAND_COLOURS[band], alpha=0.25, lw=0))
    ax.axhspan(-1, 0, color=ncap.BAND_COLOURS["green"], alpha=0.35, lw=0)
    ax.set_xlim(0, vmax + 5)
    key = lambda r: (r["controller"], _fovea(r), r["num_alphas"], r["latency_mode"])  # noqa: E731
    configs = sorted({key(r) for r in threats}, key=str)
    markers = "os^vD<>pX*"
    for i, cfg in enumerate(configs):
        pts = [r for r in threats if key(r) == cfg]
        jitter = (i - (len(configs) - 1) / 2) * 0.6
        ax.scatter(
            [r["ego_speed_kph"] + jitter for r in pts],
            [r["relative_impact_speed_kph"] or 0.0 for r in pts],
            marker=markers[i % len(markers)],
            s=18,
            label=config_label(pts[0]),
        )
    ax.set_xlabel("ego speed at the start [km/h]")
    ax.set_ylabel("relative impact speed [km/h] (0: avoided)")
    ax.set_ylim(-1, vmax)
    ax.set_title("Euro NCAP view: bands green / yellow / orange / brown / red", fontsize=9)
    _legend(ax, fontsize=6, ncol=2)
    _save(fig, path)


def _read_trace(path: Path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _num(x: str) -> float:
    return float(x) if x not in ("", None) else math.nan


def _timeline_plot(plt, path: Path, out_dir: Path, rows: list[dict], case: str | None) -> None:
    ok = [r for r in rows if r["status"] == "ok" and r["seed"] == 0]
    if case is None:
        case = next((r["scenario"] for r in ok if r["threat"]), ok[0]["scenario"] if ok else None)
    fig, axes = plt.subplots(3, 1, figsize=(7, 6.5), sharex=True)
    for r in (r for r in ok if r["scenario"] == case):
        tr = _read_trace(out_dir / r["folder"] / "trace.csv")
        t = [_num(x["t_s"]) for x in tr]
        axes[0].plot(t, [_num(x["ego_speed_kph"]) for x in tr], label=config_label(r))
        axes[1].plot(t, [_num(x["critical_ttc_s"]) for x in tr])
        axes[2].step(t, [_num(x["brake_cmd_mps2"]) + 0.3 * int(x["warning"] or 0) for x in tr], where="post")
    axes[0].set_ylabel("ego speed [km/h]")
    axes[1].set_ylabel("exact bumper TTC [s]")
    axes[1].set_ylim(0, 6)
    axes[2].set_ylabel("brake [m/s²] (+0.3: warning)")
    axes[2].set_xlabel("time [s]")
    axes[0].set_title(f"{case}: the stages of each configuration (seed 0)", fontsize=9)
    _legend(axes[0], fontsize=6, ncol=2)
    for a in axes:
        a.grid(alpha=0.3)
    _save(fig, path)
