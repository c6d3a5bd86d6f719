"""The geofence on what braking needs: an estimator measured on scenario cases, open loop.

Every case is rendered with exact ground truth and no braking (the ego keeps its speed
until the run ends as ``ScenarioSim.done`` says, a collision included). The estimator
runs on every frame pair (each frame and the one ``frame_stride`` frames before it, the
controller's default unless told), as the closed loop would with no latency, behind the geofence
controller's evidence rules (``controllers.geofence``), whose decisions are recorded but
never applied. Per case and threshold tau_i (camera-plane TTC [s] from the latest frame):

* ``fence_lag_s``: tau_i minus the critical actor's exact camera-plane TTC at the first
  frame where fence i covers at least half of its pixels (``sim.fence_lag``); None when it
  never does. With a fovea: the earlier cover of the two views, each view's own beside it
  (``fence_lag_wide_s``, ``fence_lag_fovea_s``);
* ``fence_lag_persistent_s``: the same from the first frame from which the fence covers
  half of the actor in every later frame up to contact;
* the share of the critical actor inside each fence against its exact TTC (binned in
  ``TAU_BINS_S``; the curve of ``plot_inside_share``) and, from it, ``curve_lag_s``:
  tau_i minus the TTC at which the mean share over the threat cases reaches one half
  (linear between bins). The first-cover lag rewards a fence that flickers on for a
  frame early; the curve's does not;
* on benign cases, the in-path evidence the controller would have counted ("stray"): the
  frames with an in-path region per fence and the longest run of consecutive frames, in
  either view (a frame counts when any view has a region).
"""

from __future__ import annotations

import statistics
from dataclasses import dataclass

import numpy as np

from controllers.base import BrakeCommand, Controller, Observation
from controllers.geofence import DEFAULT_FRAME_STRIDE, GeofenceConfig, GeofenceController
from scenarios.spec import ScenarioCase
from sim.camera import CameraConfig
from sim.episode import ScenarioSim
from sim.fence_lag import FenceLagMeter
from sim.latency import parse_latency
from sim.loop import ClosedLoop

TAU_BINS_S = (0.0, 0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 1.75, 2.0, 2.5, 3.0, 3.5, 4.0, 5.0)  # [s] exact tau* bins
FAST_KPH = (60.0, 80.0)  # [km/h] ego speeds of the 'fast' lag median


class OpenLoopProbe(Controller):
    """Runs ``inner`` and records what it saw and decided; never brakes."""

    needs_camera = True

    def __init__(self, inner: GeofenceController) -> None:
        self.inner = inner
        self.name = f"{inner.name}-open-loop"
        self.num_alphas = inner.num_alphas
        self.frame_stride = inner.frame_stride
        self.estimator_kind, self.cached_frames = inner.estimator_kind, inner.cached_frames

    @property
    def view_thresholds(self) -> dict[str, int]:
        return self.inner.view_thresholds

    def reset(self, calibration) -> None:
        self.inner.reset(calibration)
        self.views = self.inner.views
        self.telemetry: list[dict] = []
        self.decided: list[BrakeCommand] = []

    def act(self, obs: Observation, truth) -> BrakeCommand:
        cmd = self.inner.act(obs, None)
        self.telemetry.append(dict(cmd.telemetry))
        self.decided.append(cmd)
        return BrakeCommand(view=cmd.view, fovea_view=cmd.fovea_view)  # the maps feed the fence-lag meter only


@dataclass(frozen=True)
class CaseResult:
    name: str
    threat: bool
    ego_speed_kph: float
    fence_lag_s: dict  # '<tau>' -> lag [s] or None (the earlier cover of the views)
    fence_lag_wide_s: dict
    fence_lag_fovea_s: dict | None  # None without a fovea
    fence_lag_persistent_s: dict
    history: list  # (tau* [s], {'<tau>': share inside}) per measured frame
    stray_frames: dict  # '<tau>' -> frames with an in-path region (benign cases)
    stray_max_run: dict  # '<tau>' -> longest run of such consecutive frames
    would_warn: bool  # the controller's decisions (not applied) included a warning


def evaluate_case(
    case: ScenarioCase,
    estimator,
    thresholds_s,
    camera: CameraConfig,
    seed: int = 0,
    frame_stride: int = DEFAULT_FRAME_STRIDE,
) -> CaseResult:
    """``frame_stride`` 1: consecutive frames, the estimator's own frame interval."""
    cfg = GeofenceConfig(thresholds_s=tuple(thresholds_s), frame_stride=frame_stride)
    probe = OpenLoopProbe(GeofenceController(estimator, cfg))
    sim = ScenarioSim(case, camera, seed, render=True)
    lag = FenceLagMeter(cfg.prob_inside)
    try:
        loop = ClosedLoop(
            sim,
            parse_latency("fixed:0"),
            num_alphas=probe.num_alphas,
            pairs=True,
            frame_stride=frame_stride,
            lag_meter=lag,
        )
        loop.drive(probe)
    finally:
        sim.close()
    keys = [f"{t:g}" for t in sorted(thresholds_s)]
    stray, runs = {}, {}
    for k in keys:
        hits = [any(int(t.get(f"inpath_px_{tag}{k}s", 0)) > 0 for tag in ("", "fovea_")) for t in probe.telemetry]
        stray[k] = sum(hits)
        best = cur = 0
        for h in hits:
            cur = cur + 1 if h else 0
            best = max(best, cur)
        runs[k] = best
    warned = any(c.warning or c.decel_mps2 > 0 for c in probe.decided)
    fovea = lag.lag_s("fovea") if camera.fovea_zoom is not None else None
    return CaseResult(
        case.name,
        case.threat,
        case.ego.speed_kph,
        lag.lag_s(),
        lag.lag_s("wide"),
        fovea,
        lag.persistent_lag_s(),
        lag.history,
        stray,
        runs,
        warned,
    )


def _median(values) -> float | None:
    v = [x for x in values if x is not None]
    return round(statistics.median(v), 4) if v else None


def inside_share_curve(results: list[CaseResult], keys: list[str]) -> dict:
    """'<tau>' -> list of (bin centre [s], mean share inside, frames) over the threat cases."""
    edges = np.asarray(TAU_BINS_S)
    out = {}
    for k in keys:
        taus = np.array([t for r in results if r.threat for t, sh in r.history if k in sh])
        shares = np.array([sh[k] for r in results if r.threat for t, sh in r.history if k in sh])
        rows = []
        for lo, hi in zip(edges[:-1], edges[1:]):
            m = (taus >= lo) & (taus < hi)
            if m.any():
                rows.append([round((lo + hi) / 2, 3), round(float(shares[m].mean()), 4), int(m.sum())])
        out[k] = rows
    return out


def half_share_ttc(rows) -> float | None:
    """[(bin centre [s], mean share, frames)] ascending -> the largest TTC [s] at which the
    share reaches 0.5, linear between bins; None if it never does."""
    for j in range(len(rows) - 1, -1, -1):
        c, share, _ = rows[j]
        if share >= 0.5:
            if j == len(rows) - 1:
                return c
            c1, s1, _ = rows[j + 1]
            return c + (share - 0.5) / (share - s1) * (c1 - c)
    return None


def summarize(results: list[CaseResult], thresholds_s) -> dict:
    keys = [f"{t:g}" for t in sorted(thresholds_s)]
    threats = [r for r in results if r.threat]
    fast = [r for r in threats if FAST_KPH[0] <= r.ego_speed_kph <= FAST_KPH[1]]
    benign = [r for r in results if not r.threat]
    curve = inside_share_curve(results, keys)
    half = {k: half_share_ttc(curve[k]) for k in keys}
    return {
        "thresholds_s": [float(k) for k in keys],
        "curve_lag_s": {k: (round(float(k) - half[k], 4) if half[k] is not None else None) for k in keys},
        "fence_lag_s": {k: _median(r.fence_lag_s.get(k) for r in threats) for k in keys},
        "fence_lag_s_fast": {k: _median(r.fence_lag_s.get(k) for r in fast) for k in keys},
        "fence_lag_wide_s": {k: _median(r.fence_lag_wide_s.get(k) for r in threats) for k in keys},
        "fence_lag_fovea_s": (
            {k: _median(r.fence_lag_fovea_s.get(k) for r in threats) for k in keys}
            if any(r.fence_lag_fovea_s is not None for r in threats)
            else None
        ),
        "fence_lag_persistent_s": {k: _median(r.fence_lag_persistent_s.get(k) for r in threats) for k in keys},
        "fence_lag_persistent_s_fast": {k: _median(r.fence_lag_persistent_s.get(k) for r in fast) for k in keys},
        "fence_never_covered": {k: sum(r.fence_lag_s.get(k) is None for r in threats) for k in keys},
        "threat_cases": len(threats),
        "fast_cases": len(fast),
        "benign_cases": len(benign),
        "benign_stray_over_2_frames": {k: sum(r.stray_max_run[k] > 2 for r in benign) for k in keys},
        "benign_would_warn": sum(r.would_warn for r in benign),
        "inside_share_by_tau": curve,
        "per_case": {
            r.name: {
                "threat": r.threat,
                "ego_speed_kph": r.ego_speed_kph,
                "fence_lag_s": r.fence_lag_s,
                "fence_lag_wide_s": r.fence_lag_wide_s,
                "fence_lag_fovea_s": r.fence_lag_fovea_s,
                "fence_lag_persistent_s": r.fence_lag_persistent_s,
                # per measured frame: [tau* [s], {'<tau>': share of the actor inside, in the view
                # that covers most}]: where a fence flickers off before contact
                "cover_share_by_frame": [
                    [round(tau, 4), {k: round(v, 4) for k, v in shares.items()}] for tau, shares in r.history
                ],
                **(
                    {
                        "stray_frames": r.stray_frames,
                        "stray_max_run_frames": r.stray_max_run,
                        "would_warn": r.would_warn,
                    }
                    if not r.threat
                    else {}
                ),
            }
            for r in results
        },
    }


def format_table(summary: dict) -> str:
    keys = [f"{t:g}" for t in summary["thresholds_s"]]
    head = f"{'case':<28}" + "".join(f"{'lag@' + k + 's':>11}" for k in keys) + "   stray run (benign)"
    lines = [head, "-" * len(head)]
    for name, r in summary["per_case"].items():
        lags = "".join(
            f"{('-' if r['fence_lag_s'].get(k) is None else format(r['fence_lag_s'][k], '.2f')):>11}" for k in keys
        )
        extra = "   " + "/".join(str(r["stray_max_run_frames"][k]) for k in keys) if not r["threat"] else ""
        lines.append(f"{name:<28}{lags}{extra}")
    lines.append("-" * len(head))

    def row(label, d):
        return f"{label:<28}" + "".join(f"{('-' if d[k] is None else format(d[k], '.2f')):>11}" for k in keys)

    lines.append(row(f"median ({summary['threat_cases']} threats)", summary["fence_lag_s"]))
    lines.append(row(f"median, 60-80 km/h ({summary['fast_cases']})", summary["fence_lag_s_fast"]))
    if summary.get("fence_lag_fovea_s") is not None:
        lines.append(row("median, wide view alone", summary["fence_lag_wide_s"]))
        lines.append(row("median, fovea alone", summary["fence_lag_fovea_s"]))
    lines.append(row("median persistent lag", summary["fence_lag_persistent_s"]))
    lines.append(row("persistent, 60-80 km/h", summary["fence_lag_persistent_s_fast"]))
    lines.append(f"{'never covered':<28}" + "".join(f"{summary['fence_never_covered'][k]:>11}" for k in keys))
    lines.append(row("lag of the mean-share curve", summary["curve_lag_s"]))
    lines.append(
        "benign cases with in-path evidence over 2 frames: "
        + ", ".join(f"{k} s: {v}/{summary['benign_cases']}" for k, v in summary["benign_stray_over_2_frames"].items())
        + f"; the controller would warn in {summary['benign_would_warn']}/{summary['benign_cases']}"
    )
    return "\n".join(lines)


def plot_inside_share(summary: dict, path, title: str) -> None:
    """The share of the critical actor inside each fence against its exact TTC (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4), dpi=110)
    for k, rows in summary["inside_share_by_tau"].items():
        if rows:
            x, y, _ = zip(*rows)
            line = ax.plot(x, y, marker="o", label=f"fence {k} s")[0]
            ax.axvline(float(k), color=line.get_color(), linestyle=":", linewidth=1)
    ax.axhline(0.5, color="grey", linewidth=0.8)
    ax.set_xlabel("exact camera-plane TTC of the critical actor [s]")
    ax.set_ylabel("share of its pixels inside the fence")
    ax.set_ylim(0, 1.02)
    ax.set_title(title, fontsize=10)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
