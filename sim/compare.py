"""Two sets of closed-loop runs side by side: did any figure get worse?

A set is one or more run folders (``bittc suite`` writes a list of summaries to
``summary.json``, ``bittc run`` one summary per case folder). Runs are matched by
(scenario case, seed); a case of one set only is listed, never compared.

The figures, per family and over all matched cases, each with the direction that is
better:

* ``avoided``: threats without a collision (higher);
* ``false_alarms``: benign runs that warned or braked (lower);
* ``fcw``: threats first warned at an exact TTC >= ``FCW_TTC_S`` (higher; the criterion
  of NHTSA's stopped-lead FCW test, applied here to every threat);
* ``points``: Euro NCAP points from the impact speed (``sim.ncap_score.points``; higher);
* ``impact_kph``: the summed impact speed of the threats hit [km/h] (lower).

A case is **worse** when it collides where it did not, hits more than ``tol_kph`` harder,
alarms falsely where it was quiet, or loses its first warning at >= ``FCW_TTC_S``;
**better** the other way round. Warning and braking times that move without changing a
figure are neither. The counts (avoided, false alarms, FCW) are judged exactly; points
and the impact sum only in a family where a case's collision or impact speed changed
beyond the tolerance, so that impact speeds within it never make a figure worse.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

from bittc_core.errors import ConfigError
from sim.ncap_score import FCW_TTC_S, points
from sim.text_table import text_table

FIGURES = ("avoided", "false_alarms", "fcw", "points", "impact_kph")
COUNTS = ("avoided", "false_alarms", "fcw")  # judged exactly; the rest with the impact tolerance
LOWER_IS_BETTER = {"false_alarms", "impact_kph"}
_FLAGS = ("threat", "collision", "false_alarm")  # bool fields of a run summary
_NUMBERS = ("impact_speed_kph", "ttc_at_first_warning_s", "test_speed_kph", "points")  # number or null

Key = tuple[str, int]  # (scenario case, seed)


def _checked(s, where: str) -> dict:
    """A run summary with the fields compared here, each of its type, or ConfigError."""
    if not isinstance(s, dict):
        raise ConfigError(f"{where}: a run summary is {type(s).__name__}, not an object")
    missing = [k for k in ("scenario", "family", "seed", *_FLAGS, *_NUMBERS) if k not in s]
    if missing:
        raise ConfigError(f"{where}: a run summary lacks {', '.join(missing)}")
    name = s["scenario"]
    for k in ("scenario", "family"):
        if not isinstance(s[k], str) or not s[k]:
            raise ConfigError(f"{where}: {k} {s[k]!r} is not a name")
    if not isinstance(s["seed"], int) or isinstance(s["seed"], bool):
        raise ConfigError(f"{where}: case {name!r}: seed {s['seed']!r} is not an integer")
    for k in _FLAGS:
        if not isinstance(s[k], bool):
            raise ConfigError(f"{where}: case {name!r}: {k} {s[k]!r} is not true or false")
    for k in _NUMBERS:
        v = s[k]
        if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v)):
            raise ConfigError(f"{where}: case {name!r}: {k} {v!r} is not a number")
    return s


def load_runs(dirs: list[str | Path]) -> dict[Key, dict]:
    """(case, seed) -> summary of every run in ``dirs`` (each a folder with summary.json)."""
    runs: dict[Key, dict] = {}
    source: dict[Key, Path] = {}
    for d in dirs:
        path = Path(d) / "summary.json"
        if not path.is_file():
            raise ConfigError(f"run folder {str(d)!r}: no summary.json (a `bittc suite` or `bittc run` folder)")
        if any(p.samefile(path) for p in set(source.values())):
            raise ConfigError(f"run folder {str(d)!r} is given twice in one set")
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError) as e:
            raise ConfigError(f"{path}: not readable ({e})") from None
        except json.JSONDecodeError as e:
            raise ConfigError(f"{path}: not valid JSON ({e.msg}, line {e.lineno})") from None
        for s in data if isinstance(data, list) else [data]:
            s = _checked(s, str(path))
            key = (s["scenario"], s["seed"])
            if key in runs:
                where = f"twice in {source[key]}" if source[key] == path else f"in {source[key]} and {path}"
                raise ConfigError(f"case {key[0]!r} with seed {key[1]} is {where}: one run per case and seed in a set")
            runs[key], source[key] = s, path
    return runs


def _warned_early(s: dict) -> bool:
    t = s["ttc_at_first_warning_s"]
    return t is not None and t >= FCW_TTC_S


def _points(s: dict) -> float:
    return float(s["points"]) if s["points"] is not None else float(points(s) or 0.0)


def figures(runs: list[dict]) -> dict:
    """The figures of ``runs`` with their denominators (threats, benign)."""
    threats = [s for s in runs if s["threat"]]
    benign = [s for s in runs if not s["threat"]]
    return {
        "threats": len(threats),
        "benign": len(benign),
        "avoided": sum(not s["collision"] for s in threats),
        "false_alarms": sum(s["false_alarm"] for s in benign),
        "fcw": sum(_warned_early(s) for s in threats),
        "points": round(sum(_points(s) for s in threats), 2),
        "impact_kph": round(sum(s["impact_speed_kph"] or 0.0 for s in threats if s["collision"]), 1),
    }


def case_change(a: dict, b: dict, tol_kph: float) -> tuple[list[str], list[str], bool]:
    """-> (what got worse, what got better, whether its collision or impact speed changed
    beyond ``tol_kph``) from run ``a`` to run ``b`` of one case."""
    worse, better = [], []
    moved = a["collision"] != b["collision"]

    def judge(got_worse: bool, what: str) -> None:
        (worse if got_worse else better).append(what)

    if a["collision"] != b["collision"]:
        judge(b["collision"], "hit" if b["collision"] else "no collision" if not a["threat"] else "avoided")
    ia, ib = a["impact_speed_kph"] or 0.0, b["impact_speed_kph"] or 0.0
    if a["collision"] and b["collision"] and abs(ib - ia) > tol_kph:
        judge(ib > ia, f"impact {ia:.1f} -> {ib:.1f} km/h")
        moved = True
    if a["threat"] and _warned_early(a) != _warned_early(b):
        ta, tb = a["ttc_at_first_warning_s"], b["ttc_at_first_warning_s"]
        judge(_warned_early(a), f"first warning at TTC {_s(ta)} -> {_s(tb)} (>= {FCW_TTC_S:g} s passes)")
    if not a["threat"] and a["false_alarm"] != b["false_alarm"]:
        judge(b["false_alarm"], "false alarm" if b["false_alarm"] else "quiet")
    return worse, better, moved


def _s(t) -> str:
    return "none" if t is None else f"{t:g} s"


@dataclass
class Comparison:
    families: list[dict]  # per family, then "all": {"family", "base", "new": figures, "judged": [figure]}
    worse: dict[str, list[str]]  # case label -> what got worse (its seed in the label when not 0)
    better: dict[str, list[str]]
    only_base: list[str] = field(default_factory=list)  # cases the new set lacks
    only_new: list[str] = field(default_factory=list)

    @property
    def worse_figures(self) -> list[str]:
        """'family: figure' for every figure that got worse (the 'all' row last)."""
        out = []
        for row in self.families:
            for f in row["judged"]:
                a, b = row["base"][f], row["new"][f]
                if (b > a) if f in LOWER_IS_BETTER else (b < a):
                    out.append(f"{row['family']}: {f}")
        return out

    @property
    def passed(self) -> bool:
        """Nothing got worse, and every case of the base set is in the new one."""
        return not (self.worse or self.worse_figures or self.only_base)

    def to_dict(self) -> dict:
        return {
            "passed": self.passed,
            "families": self.families,
            "worse": self.worse,
            "better": self.better,
            "worse_figures": self.worse_figures,
            "only_base": self.only_base,
            "only_new": self.only_new,
        }


def _row(family: str, keys: list[Key], base: dict, new: dict, moved: set[Key]) -> dict:
    judged = [*COUNTS, *(("points", "impact_kph") if moved.intersection(keys) else ())]
    return {
        "family": family,
        "base": figures([base[k] for k in keys]),
        "new": figures([new[k] for k in keys]),
        "judged": judged,
    }


def compare(base: dict[Key, dict], new: dict[Key, dict], tol_kph: float = 0.5) -> Comparison:
    """Case by case and per family, over the cases in both sets."""
    if not (isinstance(tol_kph, (int, float)) and tol_kph >= 0 and math.isfinite(tol_kph)):
        raise ConfigError(f"impact tolerance {tol_kph!r} km/h: expected a number >= 0")
    common = [k for k in base if k in new]
    if not common:
        raise ConfigError("the two sets share no (case, seed): nothing to compare")
    label = {k: k[0] if k[1] == 0 else f"{k[0]} (seed {k[1]})" for k in {*base, *new}}
    worse, better, fams, moved = {}, {}, {}, set()
    for k in common:
        a, b = base[k], new[k]
        for f in ("threat", "family"):
            if a[f] != b[f]:
                raise ConfigError(f"case {label[k]!r}: {f} {a[f]!r} in the base set, {b[f]!r} in the new one")
        w, bt, m = case_change(a, b, tol_kph)
        if w:
            worse[label[k]] = w
        if bt:
            better[label[k]] = bt
        if m:
            moved.add(k)
        fams.setdefault(a["family"], []).append(k)
    rows = [_row(f, ks, base, new, moved) for f, ks in fams.items()]
    rows.append(_row("all", common, base, new, moved))
    only_base = sorted(label[k] for k in base if k not in new)
    return Comparison(rows, worse, better, only_base, sorted(label[k] for k in new if k not in base))


def _cell(row: dict, f: str) -> str:
    den = {"avoided": "threats", "fcw": "threats", "false_alarms": "benign"}.get(f)
    if not row["base"][den or "threats"]:  # points and impact speeds are the threats'
        return "-"
    a, b = row["base"][f], row["new"][f]
    shown = (lambda x: f"{x:g}") if den is None else (lambda x: f"{x}/{row['base'][den]}")
    if a == b:
        return shown(a)
    worse = (b > a) if f in LOWER_IS_BETTER else (b < a)
    verdict = ("worse" if worse else "better") if f in row["judged"] else "within tolerance"
    return f"{shown(a)} -> {shown(b)} ({verdict})"


def _n(n: int, what: str) -> str:
    return f"{n} {what}" + ("" if n == 1 else "s")


def format_comparison(c: Comparison, markdown: bool = False) -> str:
    """The per-family table, the cases that got worse and better, and the verdict."""
    head = ("family", "avoided", "false alarms", f"first warning >= {FCW_TTC_S:g} s", "points", "impact sum [km/h]")
    rows = [(r["family"], *(_cell(r, f) for f in FIGURES)) for r in c.families]
    lines = [text_table(head, rows, markdown)]
    for title, cases in (("worse", c.worse), ("better", c.better)):
        lines.append(f"\n{title} ({_n(len(cases), 'case')}):" if cases else f"\n{title}: none")
        lines += [f"  {k}: {'; '.join(v)}" for k, v in cases.items()]
    for title, names in (("missing from the new set", c.only_base), ("only in the new set", c.only_new)):
        if names:
            lines.append(f"\n{title} ({len(names)}): {', '.join(names)}")
    figs = [f for f in c.worse_figures if not f.startswith("all: ")]
    parts = [_n(len(c.worse), "case"), _n(len(figs), "family figure")] if c.worse or figs else []
    total = c.families[-1]["base"]
    verdict = " and ".join(parts) + " got worse" if c.worse or figs else "nothing got worse"
    if c.only_base:
        verdict = f"{verdict}; {len(c.only_base)} of the base set's cases are missing from the new set"
    lines.append(f"\n{verdict} ({_n(total['threats'], 'threat')} and {_n(total['benign'], 'benign run')} compared)")
    return "\n".join(lines)
