"""`bittc compare`: two sets of run folders, case by case and per family."""

from __future__ import annotations

import json

import pytest

from bittc_core.errors import ConfigError
from sim.cli import main
from sim.compare import compare, format_comparison, load_runs
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


def sets(tmp_path, new, base=BASE):
    return load_runs([write_set(tmp_path / "a", base)]), load_runs([write_set(tmp_path / "b", new)])


def test_the_summary_keys_it_reads_are_those_a_run_writes():
    for key in summary("x", "x"):
        assert key in SUMMARY_KEYS


def test_the_same_runs_compare_equal(tmp_path, capsys):
    a = write_set(tmp_path / "a", BASE)
    assert main(["compare", "--base", a, "--new", a, "--fail-on-worse"]) == 0
    assert "nothing got worse (2 threats and 1 benign run compared)" in capsys.readouterr().out


def test_a_case_that_is_hit_now_fails_the_gate(tmp_path, capsys):
    new = [summary("CCRs-50", "CCRs", collision=True, impact_speed_kph=10.0), *BASE[1:]]
    a, b = write_set(tmp_path / "a", BASE), write_set(tmp_path / "b", new)
    assert main(["compare", "--base", a, "--new", b]) == 0  # a report, not a gate, without the flag
    out = tmp_path / "c.json"
    assert main(["compare", "--base", a, "--new", b, "--fail-on-worse", "--out", str(out), "--markdown"]) == 1
    text = capsys.readouterr().out
    assert "| CCRs | 1/1 -> 0/1 (worse) | - | 1/1 | 1 -> 0.8 (worse) | 0 -> 10 (worse) |" in text
    assert "1 case and 3 family figures got worse" in text
    c = json.loads(out.read_text())
    assert c["passed"] is False and c["worse"] == {"CCRs-50": ["hit"]} and c["better"] == {}
    assert c["worse_figures"] == [f"{fam}: {f}" for fam in ("CCRs", "all") for f in ("avoided", "points", "impact_kph")]


def test_a_first_warning_that_comes_later_than_2_1_s_is_worse_and_one_sooner_better(tmp_path):
    late = [summary("CCRs-50", "CCRs", ttc_at_first_warning_s=2.0996), *BASE[1:]]
    c = compare(*sets(tmp_path, late))
    assert c.worse == {"CCRs-50": ["first warning at TTC 2.5 s -> 2.0996 s (>= 2.1 s passes)"]}
    assert c.worse_figures == ["CCRs: fcw", "all: fcw"]
    assert compare(*reversed(sets(tmp_path, late))).better == {
        "CCRs-50": [c.worse["CCRs-50"][0].replace("2.5 s -> 2.0996 s", "2.0996 s -> 2.5 s")]
    }


def test_impact_speeds_within_the_tolerance_change_no_verdict(tmp_path, capsys):
    for impact, verdict in ((19.1, None), (19.3, "worse"), (18.0, "better")):
        new = [BASE[0], summary("CCRb-12m-6mps2", "CCRb", collision=True, impact_speed_kph=impact), BASE[2]]
        c = compare(*sets(tmp_path, new))
        assert ("CCRb-12m-6mps2" in c.worse) == (verdict == "worse")
        assert ("CCRb-12m-6mps2" in c.better) == (verdict == "better")
        assert c.worse_figures == (
            ["CCRb: points", "CCRb: impact_kph", "all: points", "all: impact_kph"] if verdict == "worse" else []
        )
        assert c.passed == (verdict != "worse")
    a, b = str(tmp_path / "a"), str(tmp_path / "b")  # the last sets: 18.7 -> 18.0 km/h
    assert main(["compare", "--base", b, "--new", a, "--tol-kph", "0.5", "--fail-on-worse"]) == 1  # 0.7 km/h harder
    assert "impact 18.0 -> 18.7 km/h" in capsys.readouterr().out
    assert main(["compare", "--base", b, "--new", a, "--tol-kph", "1", "--fail-on-worse"]) == 0
    assert "18 -> 18.7 (within tolerance)" in capsys.readouterr().out


def test_false_alarms_come_and_go_and_a_benign_collision_is_worse(tmp_path):
    noisy = [*BASE[:2], summary("benign-oncoming", "benign-oncoming", threat=False, false_alarm=True)]
    a, b = sets(tmp_path, noisy)
    assert compare(a, b).worse == {"benign-oncoming": ["false alarm"]}
    assert compare(b, a).better == {"benign-oncoming": ["quiet"]}
    assert compare(a, b).worse_figures == ["benign-oncoming: false_alarms", "all: false_alarms"]
    crash = [*BASE[:2], summary("benign-oncoming", "benign-oncoming", threat=False, collision=True)]
    assert compare(*sets(tmp_path, crash)).worse == {"benign-oncoming": ["hit"]}


def test_a_case_missing_from_the_new_set_fails_the_gate(tmp_path, capsys):
    a, b = write_set(tmp_path / "a", BASE), write_set(tmp_path / "b", BASE[:2])
    assert main(["compare", "--base", a, "--new", b, "--fail-on-worse"]) == 1
    out = capsys.readouterr().out
    assert "missing from the new set (1): benign-oncoming" in out
    assert "nothing got worse; 1 of the base set's cases are missing from the new set" in out
    assert main(["compare", "--base", b, "--new", a, "--fail-on-worse"]) == 0  # a case added is no loss


def test_sets_of_several_folders_match_by_case_and_seed(tmp_path):
    single = dict(BASE[0], seed=2)  # a `bittc run` folder holds one summary, not a list
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "summary.json").write_text(json.dumps(single))
    a = load_runs([write_set(tmp_path / "suite", BASE[1:]), tmp_path / "run"])
    assert sorted(a) == [("CCRb-12m-6mps2", 0), ("CCRs-50", 2), ("benign-oncoming", 0)]
    c = compare(a, load_runs([write_set(tmp_path / "b", BASE)]))
    assert c.only_base == ["CCRs-50 (seed 2)"] and c.only_new == ["CCRs-50"]
    assert c.families[-1]["base"]["threats"] == 1
    assert "only in the new set (1): CCRs-50" in format_comparison(c)


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
        ([BASE[0], BASE[0]], "is twice in"),
        ([summary("CCRs-50", "CCRs", threat=False)], "threat True in the base set, False in the new one"),
        ([summary("CCRs-50", "CCRs-offset")], "family 'CCRs' in the base set, 'CCRs-offset' in the new one"),
        ([{"scenario": "CCRs-50"}], "lacks family, seed, threat"),
        ([dict(BASE[0], seed=None)], "seed None is not an integer"),
        ([dict(BASE[0], scenario=None)], "scenario None is not a name"),
        ([dict(BASE[0], ttc_at_first_warning_s="2.5")], "ttc_at_first_warning_s '2.5' is not a number"),
        ([dict(BASE[0], collision="no")], "collision 'no' is not true or false"),
        ([3], "a run summary is int"),
        (b"\xff\xfe", "not readable"),
        (b"[{", "not valid JSON"),
    ],
)
def test_bad_sets_are_refused_and_nothing_is_written(tmp_path, capsys, new, message):
    a = write_set(tmp_path / "a", BASE)
    if isinstance(new, bytes):
        (tmp_path / "b").mkdir()
        (tmp_path / "b" / "summary.json").write_bytes(new)
        b = str(tmp_path / "b")
    else:
        b = str(tmp_path / "b") if new is None else write_set(tmp_path / "b", new)
    out = tmp_path / "c.json"
    assert main(["compare", "--base", a, "--new", b, "--out", str(out)]) == 2
    assert message in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == (["a", "b"] if new is not None else ["a"])


def test_the_same_folder_twice_in_one_set_is_named(tmp_path, capsys):
    a = write_set(tmp_path / "a", BASE)
    assert main(["compare", "--base", a, a, "--new", a]) == 2
    assert f"run folder {a!r} is given twice in one set" in capsys.readouterr().err
    b = write_set(tmp_path / "b", BASE[:1])
    assert main(["compare", "--base", a, b, "--new", a]) == 2
    assert f"case 'CCRs-50' with seed 0 is in {a}/summary.json and {b}/summary.json" in capsys.readouterr().err


@pytest.mark.parametrize(
    "flags, message",
    [
        (["--tol-kph", "-1"], "--tol-kph"),
        (["--tol-kph", "nan"], "--tol-kph"),
        (["--out", "c.txt"], "--out 'c.txt': expected a .json file"),
        (["--out", "no/such/c.json"], "does not exist"),
        (["--out", "."], "expected a .json file"),
    ],
)
def test_bad_flags_are_refused_by_name_before_anything_is_written(tmp_path, monkeypatch, capsys, flags, message):
    a = write_set(tmp_path / "a", BASE)
    monkeypatch.chdir(tmp_path)
    assert main(["compare", "--base", a, "--new", a, *flags]) == 2
    captured = capsys.readouterr()
    assert message in captured.err and captured.out == ""
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a"]
    with pytest.raises(ConfigError, match="impact tolerance"):
        compare(load_runs([a]), load_runs([a]), tol_kph=float("nan"))
