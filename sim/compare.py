"""Two sets of closed-loop runs side by side: did any figure get worse?

A set is one or more run folders (``bittc suite`` writes a list of summaries to
``summary.json``, ``bittc run`` one summary per case folder). Runs are matched by
(scenario case, seed); a case in one set only is listed, never compared.

The figures, per family and over all matched cases, each with the direction that is
better:

* ``avoided``: threats without a collision (higher);
* ``false_alarms``: benign runs that warned or braked (lower);
* ``fcw``: threats first warned at an exact TTC >= ``FCW_TTC_S`` (higher; NHTSA's
  forward-collision-warning test);
* ``points``: Euro NCAP points from the impact speed (``sim.ncap_score.points``; higher);
* ``impact_kph``: the summed impact speed of the threats hit [km/h] (lower).

A case is **worse** when it collides where it did not, hits more than ``tol_kph`` harder,
alarms falsely where it was quiet, or loses its warning at >= ``FCW_TTC_S``; **better**
the other way round. Warning and braking times that move without changing a figure are
neither.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

from bittc_core.errors import ConfigError

FCW_TTC_S = 2.1  # [s] a first warning at an exact TTC at least this early passes (NHTSA FCW)
FIGURES = ("avoided", "false_alarms", "fcw", "points", "impact_kph")
LOWER_IS_BETTER = {"false_alarms", "impact_kph"}
_KEYS = ("scenario", "family", "seed", "threat", "collision", "impact_speed_kph", "false_alarm")

Key = tuple[str, int]  # (scenario case, seed)


def load_runs(dirs: list[str | Path]) -> dict[Key, dict]:
    """(case, seed) -> summary of every run in ``dirs`` (each a folder with summary.json)."""
    runs: dict[Key, dict] = {}
    for d in dirs:
        path = Path(d) / "summary.json"
        if not path.is_file():
            raise ConfigError(f"run folder {str(d)!r}: no summary.json (a `bittc suite` or `bittc run` folder)")
        try:
            data = json.loads(path.read_text())
        except json.JSONDecodeError as e:
            raise ConfigError(f"{path}: not valid JSON ({e.msg}, line {e.lineno})") from None
        for s in data if isinstance(data, list) else [data]:
            missing = [k for k in _KEYS if not isinstance(s, dict) or k not in s]
            if missing:
                raise ConfigError(f"{path}: a run summary lacks {', '.join(missing)}")
            key = (str(s["scenario"]), int(s["seed"]))
            if key in runs:
                raise ConfigError(
                    f"{path}: case {key[0]!r} with seed {key[1]} appears twice in one set "
                    "(compare one controller, K and latency at a time)"
                )
            runs[key] = s
    return runs


def _warned_early(s: dict) -> bool:
    t = s.get("ttc_at_first_warning_s")
    return t is not None and t >= FCW_TTC_S


def _points(s: dict) -> float:
    from sim.ncap_score import points

    p = s.get("points")
    return float(p) if p is not None else float(points(s) or 0.0)


def figures(runs: list[dict]) -> dict:
    """The figures of ``runs`` with their denominators (threats, benign)."""
    threats = [s for s in runs if s["threat"]]
    benign = [s for s in runs if not s["threat"]]
    return {
        "threats": len(threats),
        "benign": len(benign),
        "avoided": sum(not s["collision"] for s in threats),
        "false_alarms": sum(bool(s["false_alarm"]) for s in benign),
        "fcw": sum(_warned_early(s) for s in threats),
        "points": round(sum(_points(s) for s in threats), 2),
        "impact_kph": round(sum(s["impact_speed_kph"] or 0.0 for s in threats if s["collision"]), 1),
    }


def case_change(a: dict, b: dict, tol_kph: float) -> tuple[list[str], list[str]]:
    """-> (what got worse, what got better) from run ``a`` to run ``b`` of one case."""
    worse, better = [], []

    def judge(got_worse: bool, got_better: bool, what: str) -> None:
        (worse if got_worse else better if got_better else []).append(what)

    if a["threat"]:
        ia, ib = a["impact_speed_kph"] or 0.0, b["impact_speed_kph"] or 0.0
        if a["collision"] != b["collision"]:
            judge(b["collision"], a["collision"], "hit" if b["collision"] else "avoided")
        if a["collision"] and b["collision"] and abs(ib - ia) > tol_kph:
            judge(ib > ia, ib < ia, f"impact {ia:.1f} -> {ib:.1f} km/h")
        ea, eb = _warned_early(a), _warned_early(b)
        if ea != eb:
            ta, tb = a.get("ttc_at_first_warning_s"), b.get("ttc_at_first_warning_s")
            judge(ea, eb, f"first warning at TTC {_s(ta)} -> {_s(tb)}")
    elif bool(a["false_alarm"]) != bool(b["false_alarm"]):
        judge(bool(b["false_alarm"]), bool(a["false_alarm"]), "false alarm" if b["false_alarm"] else "quiet")
    return worse, better


def _s(t) -> str:
    return "none" if t is None else f"{t:.2f} s"


@dataclass
class Comparison:
    families: list[dict]  # per family, then "all": {"family", "base": figures, "new": figures}
    worse: dict[str, list[str]]  # case -> what got worse (seed in the case label when not 0)
    better: dict[str, list[str]]
    only_base: list[str] = field(default_factory=list)
    only_new: list[str] = field(default_factory=list)

    @property
    def worse_figures(self) -> list[str]:
        """'family: figure' for every figure that got worse."""
        out = []
        for row in self.families:
            for f in FIGURES:
                a, b = row["base"][f], row["new"][f]
                if (b > a) if f in LOWER_IS_BETTER else (b < a):
                    out.append(f"{row['family']}: {f}")
        return out

    def to_dict(self) -> dict:
        return {
            "families": self.families,
            "worse": self.worse,
            "better": self.better,
            "worse_figures": self.worse_figures,
            "only_base": self.only_base,
            "only_new": self.only_new,
        }


def compare(base: dict[Key, dict], new: dict[Key, dict], tol_kph: float = 0.5) -> Comparison:
    """Case by case and per family, over the cases in both sets."""
    if not tol_kph >= 0:
        raise ConfigError(f"impact tolerance {tol_kph!r} km/h: expected a number >= 0")
    common = [k for k in base if k in new]
    if not common:
        raise ConfigError("the two sets share no (case, seed): nothing to compare")
    label = {k: k[0] if k[1] == 0 else f"{k[0]} (seed {k[1]})" for k in {*base, *new}}
    worse, better, fams = {}, {}, {}
    for k in common:
        a, b = base[k], new[k]
        if a["threat"] != b["threat"]:
            raise ConfigError(f"case {label[k]!r} is a threat in one set and benign in the other")
        w, bt = case_change(a, b, tol_kph)
        if w:
            worse[label[k]] = w
        if bt:
            better[label[k]] = bt
        fams.setdefault(a["family"], []).append(k)
    rows = [
        {"family": f, "base": figures([base[k] for k in ks]), "new": figures([new[k] for k in ks])} for f, ks in fams.items()
    ]
    rows.append({"family": "all", "base": figures([base[k] for k in common]), "new": figures([new[k] for k in common])})
    return Comparison(
        rows,
        worse,
        better,
        sorted(label[k] for k in base if k not in new),
        sorted(label[k] for k in new if k not in base),
    )


def _cell(row: dict, f: str) -> str:
    a, b = row["base"][f], row["new"][f]
    den = {"avoided": "threats", "fcw": "threats", "false_alarms": "benign"}.get(f)
    if not row["base"][den or "threats"]:  # points and impact speeds are the threats'
        return "-"
    fmt = (lambda x: f"{x:g}") if f in ("points", "impact_kph") else str
    tail = f"/{row['base'][den]}" if den else ""
    if a == b:
        return f"{fmt(a)}{tail}"
    mark = "worse" if ((b > a) if f in LOWER_IS_BETTER else (b < a)) else "better"
    return f"{fmt(a)} -> {fmt(b)}{tail} ({mark})"


def format_comparison(c: Comparison, markdown: bool = False) -> str:
    """The per-family table, then the cases that got worse and better."""
    head = ("family", "avoided", "false alarms", f"FCW >= {FCW_TTC_S} s", "points", "impact sum [km/h]")
    rows = [(r["family"], *(_cell(r, f) for f in FIGURES)) for r in c.families]
    if markdown:
        lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        lines += ["| " + " | ".join(r) + " |" for r in rows]
    else:
        widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(head)]
        fmt = "  ".join(f"{{:<{w}}}" for w in widths)
        lines = [fmt.format(*head)] + [fmt.format(*r) for r in rows]
    for title, cases in (("worse", c.worse), ("better", c.better)):
        lines.append(f"\n{title} ({_n(len(cases), 'case')}):" if cases else f"\n{title}: none")
        lines += [f"  {k}: {'; '.join(v)}" for k, v in cases.items()]
    for title, names in (("only in the base set", c.only_base), ("only in the new set", c.only_new)):
        if names:
            lines.append(f"\n{title} ({len(names)}): {', '.join(names)}")
    verdict = "nothing got worse" if not (c.worse or c.worse_figures) else (
        f"{_n(len(c.worse), 'case')} and {_n(len(c.worse_figures), 'figure')} got worse"
    )
    total = c.families[-1]["base"]
    lines.append(f"\n{verdict} ({_n(total['threats'], 'threat')} and {_n(total['benign'], 'benign run')} compared)")
    return "\n".join(lines)


def _n(n: int, what: str) -> str:
    return f"{n} {what}" + ("" if n == 1 else "s")
