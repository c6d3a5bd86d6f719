"""`bittc compare`: two sets of run folders, case by case and per family."""

from __future__ import annotations

import json

import pytest

from bittc_core.errors import ConfigError
from sim.cli import main
from sim.compare import compare, load_runs
from sim.run_summary import SUMMARY_KEYS


def summary(case: str, family: str, threat: bool = True, **kw) -> dict:
    s = {
        "scenario": case,
        "family": family,
        "seed": 0,
        "threat": threat,
        "collision": False,
        "impact_speed_kph": None,
        "false_alarm": False,
        "ttc_at_first_warning_s": 2.5 if threat else None,
        "test_speed_kph": 50.0 if threat else None,
        "points": None,
    }
    s.update(kw)
    if threat:
        s["points"] = 1.0 if not s["collision"] else round(1 - s["impact_speed_kph"] / s["test_speed_kph"], 4)
    return s


def write_set(path, runs) -> str:
    path.mkdir(parents=True, exist_ok=True)
    (path / "summary.json").write_text(json.dumps(runs))
    return str(path)


BASE = [
    summary("CCRs-50", "CCRs"),
    summary("CCRb-12m-6mps2", "CCRb", collision=True, impact_speed_kph=18.7),
    summary("benign-oncoming", "benign-oncoming", threat=False),
]


def test_the_summary_keys_it_reads_are_those_a_run_writes():
    for key in ("scenario", "family", "seed", "threat", "collision", "impact_speed_kph", "false_alarm", "points"):
        assert key in SUMMARY_KEYS


def test_the_same_runs_compare_equal(tmp_path, capsys):
    a = write_set(tmp_path / "a", BASE)
    assert main(["compare", "--base", a, "--new", a, "--fail-on-worse"]) == 0
    out = capsys.readouterr().out
    assert "nothing got worse (2 threats and 1 benign run compared)" in out


@pytest.mark.parametrize(
    "change, worse",
    [
        ({"collision": True, "impact_speed_kph": 10.0}, ["hit", "impact"]),  # avoided -> hit
        ({"ttc_at_first_warning_s": 1.9}, ["first warning at TTC 2.50 s -> 1.90 s"]),
    ],
)
def test_a_threat_that_got_worse_fails_the_gate(tmp_path, capsys, change, worse):
    new = [summary("CCRs-50", "CCRs", **change), *BASE[1:]]
    a, b = write_set(tmp_path / "a", BASE), write_set(tmp_path / "b", new)
    assert main(["compare", "--base", a, "--new", b]) == 0  # a report, not a gate, without the flag
    assert main(["compare", "--base", a, "--new", b, "--fail-on-worse", "--out", str(tmp_path / "c.json")]) == 1
    c = json.loads((tmp_path / "c.json").read_text())
    assert list(c["worse"]) == ["CCRs-50"] and c["better"] == {}
    assert all(any(w in got for got in c["worse"]["CCRs-50"]) for w in worse[:1])
    assert "CCRs: " + ("avoided" if "collision" in change else "fcw") in c["worse_figures"]
    assert "all: " + ("avoided" if "collision" in change else "fcw") in c["worse_figures"]


def test_impact_speeds_within_the_tolerance_are_the_same(tmp_path):
    for impact, worse in ((19.1, False), (19.3, True), (18.0, False)):
        new = [BASE[0], summary("CCRb-12m-6mps2", "CCRb", collision=True, impact_speed_kph=impact), BASE[2]]
        c = compare(load_runs([write_set(tmp_path / "a", BASE)]), load_runs([write_set(tmp_path / "b", new)]))
        assert ("CCRb-12m-6mps2" in c.worse) == worse
        assert ("CCRb-12m-6mps2" in c.better) == (impact < 18.2)


def test_false_alarms_come_and_go(tmp_path):
    noisy = [*BASE[:2], summary("benign-oncoming", "benign-oncoming", threat=False, false_alarm=True)]
    a, b = load_runs([write_set(tmp_path / "a", BASE)]), load_runs([write_set(tmp_path / "b", noisy)])
    assert compare(a, b).worse == {"benign-oncoming": ["false alarm"]}
    assert compare(b, a).better == {"benign-oncoming": ["quiet"]}
    assert compare(a, b).worse_figures == ["benign-oncoming: false_alarms", "all: false_alarms"]


def test_sets_of_several_folders_match_by_case_and_seed(tmp_path):
    single = dict(BASE[0], seed=2)  # a `bittc run` folder holds one summary, not a list
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "summary.json").write_text(json.dumps(single))
    a = load_runs([write_set(tmp_path / "suite", BASE[1:]), tmp_path / "run"])
    assert sorted(a) == [("CCRb-12m-6mps2", 0), ("CCRs-50", 2), ("benign-oncoming", 0)]
    c = compare(a, load_runs([write_set(tmp_path / "b", BASE)]))
    assert c.only_base == ["CCRs-50 (seed 2)"] and c.only_new == ["CCRs-50"]
    assert c.families[-1]["base"]["threats"] == 1


def test_a_real_run_folder_compares_with_itself(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["run", "CCRs-20", "--controller", "oracle", "--out", str(out)]) == 0
    capsys.readouterr()
    assert main(["compare", "--base", str(out), "--new", str(out), "--fail-on-worse"]) == 0
    assert "nothing got worse (1 threat and 0 benign runs compared)" in capsys.readouterr().out


@pytest.mark.parametrize(
    "new, message",
    [
        (None, "no summary.json"),
        ([summary("CCRs-30", "CCRs")], "share no (case, seed)"),
        ([BASE[0], BASE[0]], "appears twice in one set"),
        ([summary("CCRs-50", "CCRs", threat=False)], "a threat in one set and benign in the other"),
        ([{"scenario": "CCRs-50"}], "lacks family, seed, threat"),
    ],
)
def test_bad_sets_are_refused_and_nothing_is_written(tmp_path, capsys, new, message):
    a = write_set(tmp_path / "a", BASE)
    b = str(tmp_path / "b") if new is None else write_set(tmp_path / "b", new)
    out = tmp_path / "c.json"
    assert main(["compare", "--base", a, "--new", b, "--out", str(out)]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


def test_bad_flags_are_refused_by_name(tmp_path, capsys):
    a = write_set(tmp_path / "a", BASE)
    assert main(["compare", "--base", a, "--new", a, "--tol-kph", "-1"]) == 2
    assert "--tol-kph" in capsys.readouterr().err
    assert main(["compare", "--base", a, "--new", a, "--out", str(tmp_path / "c.txt")]) == 2
    assert "--out" in capsys.readouterr().err
    assert not (tmp_path / "c.txt").exists()
    with pytest.raises(ConfigError, match="impact tolerance"):
        compare(load_runs([a]), load_runs([a]), tol_kph=float("nan"))
