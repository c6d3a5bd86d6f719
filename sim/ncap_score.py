"""Scoring a suite the way Euro NCAP scores it: per family, and points from the impact
speed, with the cases that no braking can avoid marked with their reason.

Points of a threat case (Euro NCAP's AEB VRU and Car-to-Car rating award a test speed's
points from the impact speed reduction): 1 when avoided, else the share of the test speed
shed before the impact, 1 - v_impact / v_test (0 without any reduction).

Unavoidable: a case is unavoidable when the ego braking fully from the first instant of
the run (no detection delay, the actuator's delay and jerk limit only) still touches the
target; its reason says how.
"""

from __future__ import annotations

from collections import defaultdict
from functools import lru_cache

from controllers.stages import MAX_DECEL_MPS2
from scenarios.spec import ScenarioCase
from sim.camera import CameraConfig
from sim.text_table import text_table

#: [s] a first warning at an exact TTC at least this early passes: the criterion of NHTSA's
#: FCW confirmation test for a stopped lead, reported beside Euro NCAP's figures
FCW_TTC_S = 2.1


@lru_cache(maxsize=512)
def unavoidable_reason(case: ScenarioCase) -> str | None:
    """Why no braking avoids ``case`` (None when full braking from the start does)."""
    if not case.threat or case.ego.speed_kph == 0:
        return None
    from sim.episode import ScenarioSim

    sim = ScenarioSim(case, CameraConfig(), seed=0, render=False)
    try:
        sim.reset()
        while sim.collision is None and sim.t_s < case.duration_s - 1e-9:
            sim.substep(MAX_DECEL_MPS2)  # a stopped ego waits: whatever touches it then is the target's doing
        col = sim.collision
    finally:
        sim.close()
    if col is None:
        return None
    if col.impact_speed_mps < 0.5:
        return "the target drives into the ego stopped by full braking from the start"
    return f"full braking from the start still hits at {col.impact_speed_mps * 3.6:.0f} km/h"


def points(summary: dict) -> float | None:
    """A threat case's points in [0, 1] from its impact speed (None for a benign case)."""
    if not summary["threat"]:
        return None
    if not summary["collision"]:
        return 1.0
    test = summary.get("test_speed_kph") or 0.0
    if test <= 0:
        return 0.0
    return round(max(0.0, 1.0 - (summary["impact_speed_kph"] or 0.0) / test), 4)


def impact_share(summaries: list[dict]) -> float | None:
    """The mean impact speed of the threats hit that braking could avoid, as a share of
    each one's test speed (None when there is none)."""
    hits = [s for s in summaries if s["threat"] and s["collision"] and not s.get("unavoidable")]
    shares = [(s["impact_speed_kph"] or 0.0) / s["test_speed_kph"] for s in hits if s.get("test_speed_kph")]
    return sum(shares) / len(shares) if shares else None


def family_rows(summaries: list[dict]) -> list[dict]:
    """One row per family, in first-seen order: cases, threats avoided, avoidable threats,
    false alarms, mean impact speed of the collisions [km/h], points and their maximum."""
    fams: dict[str, list[dict]] = defaultdict(list)
    for s in summaries:
        fams[s["family"]].append(s)
    rows = []
    for fam, ss in fams.items():
        threats = [s for s in ss if s["threat"]]
        hits = [s["impact_speed_kph"] for s in threats if s["collision"]]
        pts = [points(s) for s in threats]
        rows.append(
            {
                "family": fam,
                "cases": len(ss),
                "threats": len(threats),
                "avoided": sum(not s["collision"] for s in threats),
                "avoidable": sum(not s.get("unavoidable") for s in threats),
                "false_alarms": sum(bool(s["false_alarm"]) for s in ss if not s["threat"]),
                "benign": len(ss) - len(threats),
                "mean_impact_kph": round(sum(hits) / len(hits), 2) if hits else None,
                "points": round(sum(pts), 2) if threats else None,
            }
        )
    return rows


def format_family_rows(summaries: list[dict], markdown: bool = False) -> str:
    """The per-family table: avoided / threats (avoidable ones), false alarms, mean impact, points."""
    head = ("family", "avoided", "avoidable", "FA", "impact kph", "points")

    def cells(r: dict) -> tuple[str, ...]:
        return (
            r["family"],
            f"{r['avoided']}/{r['threats']}" if r["threats"] else "-",
            str(r["avoidable"]) if r["threats"] else "-",
            f"{r['false_alarms']}/{r['benign']}" if r["benign"] else "-",
            "-" if r["mean_impact_kph"] is None else f"{r['mean_impact_kph']:.1f}",
            "-" if r["points"] is None else f"{r['points']:.2f}/{r['threats']}",
        )

    return text_table(head, [cells(r) for r in family_rows(summaries)], markdown)
