"""Euro NCAP's view of a threat run: the 2026 colour band of its relative impact speed,
and the gate on the low-speed CCRs cases.

Source: Euro NCAP's published rating code for 2026, github.com/Euro-NCAP/euroncap_rating_2026
(commit 94b1035), which implements the Frontal Collisions assessment protocol:
- the band of a car-to-car rear test point (CCRs, CCRm, CCRb; criterion "mitigation or
  avoidance", measured as the relative impact speed) is chosen by the speed of the
  vehicle under test, rows of 10, 20, 30, 40 and >= 50 km/h
  (``crash_avoidance/matrix_processing.py``: ``ComputedTestPoint._compute_color_logic``,
  ``get_band_color``); upper edges inclusive, after rounding to 0.01 km/h:

  =========  =====  ===========  ===========  ===========  ======
  VUT speed  green  yellow       orange       brown        red
  =========  =====  ===========  ===========  ===========  ======
  10, 20     0      -            -            -            > 0
  30         0      -            -            (0, 10]      > 10
  40         0      -            (0, 10]      (10, 20]     > 20
  >= 50      0      (0, 10]      (10, 20]     (20, 30]     > 30
  =========  =====  ===========  ===========  ===========  ======

  The band scores 100 / 75 / 50 / 25 / 0 % of a point (``TestPoint.predicted_score``).
  The code's 2 km/h tolerance applies when a tested colour is compared with the maker's
  prediction; there is no prediction here, so the band is the true colour, as
  ``get_band_color`` gives it.
- the gate (``crash_avoidance/compute_score.py``: ``check_general_requirements_rules``):
  every standard-range CCRs test point at a VUT speed <= 20 km/h must be green, or every
  Frontal Collisions score is zero. Euro NCAP applies it to the maker's predicted
  colours; here it is applied to the simulated outcomes of the CCRs and CCRs-offset
  cases at <= 20 km/h (a sweep without such a case has no gate: None).
- Euro NCAP does not score a forward-collision warning in the car-to-car rear tests;
  the FCW figure of the summary is NHTSA's (``sim.sweep.tables``).
"""

from __future__ import annotations

import math

BANDS = ("green", "yellow", "orange", "brown", "red")
BAND_COLOURS = {"green": "#2e9d3a", "yellow": "#f1c40f", "orange": "#e67e22", "brown": "#8b5a2b", "red": "#c0392b"}
#: VUT speed row [km/h] -> upper edges [km/h] of (yellow, orange, brown); None: the band is not used
_ROWS = {
    10: (None, None, None),
    20: (None, None, None),
    30: (None, None, 10.0),
    40: (None, 10.0, 20.0),
    50: (10.0, 20.0, 30.0),
}
CAR_TO_CAR_FAMILIES = ("CCRs", "CCRs-offset", "CCRm", "CCRb")
GATE_FAMILIES = ("CCRs", "CCRs-offset")
GATE_MAX_SPEED_KPH = 20.0


def speed_row(vut_speed_kph: float) -> int:
    """The band row of a VUT speed: the largest row at or below it (>= 50 km/h: 50)."""
    rows = [r for r in sorted(_ROWS) if r <= vut_speed_kph + 1e-9]
    return rows[-1] if rows else min(_ROWS)


def band(relative_impact_speed_kph: float, vut_speed_kph: float) -> str:
    """The 2026 colour of a car-to-car rear test point (0 km/h: avoided, green)."""
    v = round(float(relative_impact_speed_kph), 2)
    if not math.isfinite(v) or v < 0:
        raise ValueError(f"relative impact speed {relative_impact_speed_kph!r} km/h: must be finite and >= 0")
    if v <= 0:
        return "green"
    for name, upper in zip(BANDS[1:4], _ROWS[speed_row(vut_speed_kph)]):
        if upper is not None and v <= upper:
            return name
    return "red"


def band_of_run(row: dict) -> str | None:
    """The band of a results row of a car-to-car rear case; None for other cases."""
    if row.get("family") not in CAR_TO_CAR_FAMILIES or not row.get("threat"):
        return None
    v = (row.get("relative_impact_speed_kph") or 0.0) if row.get("collision") else 0.0
    return band(v, row["ego_speed_kph"])


def ccrs_gate(threat_rows: list[dict]) -> bool | None:
    """True when every CCRs / CCRs-offset run at <= 20 km/h is green; None without such runs."""
    low = [r for r in threat_rows if r.get("family") in GATE_FAMILIES and r["ego_speed_kph"] <= GATE_MAX_SPEED_KPH]
    if not low:
        return None
    return all(r.get("ncap_band") == "green" for r in low)


def band_regions(vmax_kph: float) -> list[tuple[float, float, float, float, str]]:
    """(x0, x1, y0, y1, band) rectangles for a plot of relative impact speed (y) against
    VUT speed (x): each row drawn from halfway to the row below it."""
    out = []
    rows = sorted(_ROWS)
    for i, r in enumerate(rows):
        x0 = 0.0 if i == 0 else (rows[i - 1] + r) / 2
        x1 = vmax_kph + 10 if i == len(rows) - 1 else (r + rows[i + 1]) / 2
        lo = 0.0
        for name, upper in zip(BANDS[1:4], _ROWS[r]):
            if upper is not None:
                out.append((x0, x1, lo, upper, name))
                lo = upper
        out.append((x0, x1, lo, vmax_kph + 10, "red"))
    return out
