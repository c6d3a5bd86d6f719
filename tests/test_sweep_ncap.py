"""Euro NCAP's car-to-car rating bands and gate (``sim.sweep.ncap``), and the suites the sweep runs."""

from __future__ import annotations

import pytest

from sim.sweep import ncap


@pytest.mark.parametrize(
    "rel,vut,expected",
    [
        (0.0, 80, "green"),
        (0.004, 50, "green"),  # rounds to 0.00
        (10.0, 50, "yellow"),
        (10.01, 50, "orange"),
        (20.0, 60, "orange"),
        (25.0, 80, "brown"),
        (30.01, 50, "red"),
        (5.0, 40, "orange"),
        (15.0, 40, "brown"),
        (20.5, 40, "red"),
        (10.0, 30, "brown"),
        (10.5, 30, "red"),
        (0.5, 20, "red"),
        (3.0, 10, "red"),
    ],
)
def test_ncap_2026_bands(rel, vut, expected):
    assert ncap.band(rel, vut) == expected


def test_ncap_band_refuses_nonsense():
    with pytest.raises(ValueError, match="nan"):
        ncap.band(float("nan"), 50)


def test_ncap_gate_needs_every_low_speed_ccrs_green():
    rows = [
        {"family": "CCRs", "ego_speed_kph": 10, "ncap_band": "green"},
        {"family": "CCRs", "ego_speed_kph": 20, "ncap_band": "green"},
        {"family": "CCRs", "ego_speed_kph": 50, "ncap_band": "red"},  # above the gate's range
        {"family": "CCRm", "ego_speed_kph": 20, "ncap_band": "red"},  # not a CCRs case
    ]
    assert ncap.ccrs_gate(rows) is True
    rows[1]["ncap_band"] = "red"
    assert ncap.ccrs_gate(rows) is False
    assert ncap.ccrs_gate([{"family": "CCRm", "ego_speed_kph": 20, "ncap_band": "red"}]) is None


def test_demo_suite_is_what_the_help_says():
    import scenarios

    cases = [c.name for c in scenarios.resolve_suite("demo")]
    assert cases == list(scenarios.DEMO_CASES)
    assert all(name in scenarios.SUITES["demo"] for name in cases)
    assert {c.family for c in scenarios.resolve_suite("demo")} >= {"CCRs", "CPLA", "CCFtap"}
    assert any(not c.threat for c in scenarios.resolve_suite("demo"))


def test_ncap_suite_has_every_car_to_car_case():
    import scenarios

    names = {c.name for c in scenarios.resolve_suite("ncap")}
    fams = {c.family for c in scenarios.resolve_suite("ncap")}
    assert fams == set(ncap.CAR_TO_CAR_FAMILIES)
    assert {"CCRs-10", "CCRs-80", "CCRm-30", "CCRm-80"} <= names
    assert not [c for c in scenarios.resolve_suite("benign") if c.threat]
