"""`bittc sweep`: settings checks, identical results whatever the workers, the backend or an
interruption, failed runs recorded, and the results' columns (the rating bands and suites:
test_sweep_ncap.py)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from bittc_core.errors import ConfigError
from sim.cli import main
from sim.sweep.plan import SweepSettings, check_settings, plan_runs
from sim.sweep.sweep import run_sweep

TINY = """\
name: tiny
description: "short cases for the sweep tests"
threat: true
case_name: "tiny-{ego_speed_kph}"
duration_s: 2.5
ego: {speed_kph: [20, 30]}
actors:
  - {vehicle: gvt, lane: 0, speed_kph: 0, overlap_pct: 100, headway_s: 2}
"""

RAISING = """\
from controllers.base import BrakeCommand, Controller


class Raising(Controller):
    name = "raising"

    def act(self, obs, truth):
        raise RuntimeError("this controller always fails")
"""


@pytest.fixture
def tiny(tmp_path) -> str:
    path = tmp_path / "tiny.yaml"
    path.write_text(TINY)
    return str(path)


def _settings(tiny: str, **kw) -> SweepSettings:
    base = dict(suites=(tiny,), controllers=("oracle", "none"), num_alphas=(1,), latencies=("fixed:50",))
    return SweepSettings(**(base | kw))


# --- settings --------------------------------------------------------------------------


@pytest.mark.parametrize(
    "kw,needle",
    [
        (dict(suites=("no-such-suite",)), "no-such-suite"),
        (dict(controllers=("oracle", "brakebot")), "brakebot"),
        (dict(latencies=("sometimes",)), "sometimes"),
        (dict(num_alphas=()), "num_alphas"),
        (dict(num_alphas=(4, 0)), "K = 0"),
        (dict(seeds=0), "seeds: 0"),
        (dict(video_cases=("CCRs-50",)), "CCRs-50"),
    ],
)
def test_bad_settings_name_the_value(tiny, kw, needle):
    with pytest.raises(ConfigError, match=needle):
        check_settings(_settings(tiny, **kw))


@pytest.mark.parametrize(
    "extra,needle",
    [
        (["--suite", "nope"], "'nope'"),
        (["--controllers", "brakebot"], "brakebot"),
        (["--latency", "fixed:-5"], "-5"),
        (["--num-alphas", "0"], "--num-alphas: K = 0"),
        (["--seeds", "0"], "--seeds: 0"),
        (["--workers", "0"], "workers 0"),
    ],
)
def test_cli_refuses_bad_input_before_any_run(tmp_path, capsys, extra, needle):
    out = tmp_path / "sw"
    argv = ["sweep", "--suite", "CCRs-20", "--controllers", "oracle", "--latency", "fixed:50", "--out", str(out)]
    argv += extra
    assert main(argv) == 2
    assert needle in capsys.readouterr().err
    assert not out.exists() or not any(out.iterdir())


def test_cli_says_how_to_install_ray(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray raises ImportError
    argv = ["sweep", "--suite", "CCRs-20", "--controllers", "oracle", "--out", str(tmp_path / "sw"), "--backend", "ray"]
    assert main(argv) == 2
    assert "pip install -e '.[ray]'" in capsys.readouterr().err
    assert not (tmp_path / "sw").exists()


def test_plan_lists_every_run_once_in_a_fixed_order(tiny):
    s = _settings(
        tiny, controllers=("geofence", "oracle"), num_alphas=(1, 4), latencies=("fixed:50", "measured"), seeds=2
    )
    plan = plan_runs(s, check_settings(s))
    # 2 cases x (geofence: 2 K + oracle: 1) x 2 latency modes x 2 seeds
    assert len(plan) == 2 * 3 * 2 * 2
    assert len({p.run_id for p in plan}) == len(plan)
    assert [p.index for p in plan] == list(range(len(plan)))
    assert plan[0].run_id == "geofence-K1-fixed_50/tiny-20-s0"
    assert {p.num_alphas for p in plan if p.controller == "oracle"} == {0}


def test_out_holding_another_sweep_is_refused(tiny, tmp_path):
    out = tmp_path / "sw"
    run_sweep(_settings(tiny, controllers=("none",)), out, progress=False)
    with pytest.raises(ConfigError, match="other settings"):
        run_sweep(_settings(tiny, controllers=("oracle",)), out, resume=True, progress=False)
    with pytest.raises(ConfigError, match="already"):
        run_sweep(_settings(tiny, controllers=("none",)), out, progress=False)
    other = tmp_path / "other"
    other.mkdir()
    (other / "notes.txt").write_text("mine")
    with pytest.raises(ConfigError, match="not empty"):
        run_sweep(_settings(tiny, controllers=("none",)), other, progress=False)


# --- determinism, resume, failures ---------------------------------------------------------


def test_one_and_two_workers_give_identical_results(tiny, tmp_path):
    import torch

    s = _settings(tiny, controllers=("geofence", "oracle"), num_alphas=(1,))
    torch.set_num_threads(1)
    a = run_sweep(s, tmp_path / "w1", workers=1, progress=False)
    assert torch.get_num_threads() == 1  # run in this process: the caller's thread count back
    b = run_sweep(s, tmp_path / "w2", workers=2, progress=False)
    assert not a.failed and not b.failed
    results = (tmp_path / "w1" / "results.csv").read_bytes()
    assert results == (tmp_path / "w2" / "results.csv").read_bytes()
    assert (tmp_path / "w1" / "summary.md").read_bytes() == (tmp_path / "w2" / "summary.md").read_bytes()
    assert results.count(b"\n") == 1 + 2 * 2  # header + 2 cases x 2 controllers
    report = (tmp_path / "w1" / "report.html").read_text()
    for png in sorted((tmp_path / "w1" / "plots").glob("*.png")):
        assert f"plots/{png.name}" in report


@pytest.mark.slow  # a sweep killed and resumed, then run whole: about 45 s; CI runs it with -m slow
def test_resume_after_a_kill_gives_the_same_results(tiny, tmp_path):
    args = [
        "--suite",
        tiny,
        "--controllers",
        "oracle",
        "none",
        "geofence",
        "--num-alphas",
        "1",
        "--latency",
        "fixed:50",
        "fixed:100",
    ]
    whole = tmp_path / "whole"
    assert main(["sweep", *args, "--out", str(whole)]) == 0
    cut = tmp_path / "cut"
    env = dict(os.environ, SDL_VIDEODRIVER="dummy")
    proc = subprocess.Popen(
        [sys.executable, "-m", "sim.cli", "sweep", *args, "--out", str(cut)],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and not list(cut.glob("runs/*/*/summary.json")):
        time.sleep(0.02)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    finished = list(cut.glob("runs/*/*/summary.json"))
    assert finished and not (cut / "results.csv").exists(), "the sweep was not cut mid-way"
    assert main(["sweep", *args, "--out", str(cut)]) == 2  # not without --resume
    assert main(["sweep", *args, "--out", str(cut), "--resume"]) == 0
    assert (cut / "results.csv").read_bytes() == (whole / "results.csv").read_bytes()
    assert not list(cut.glob("runs/*/.*.partial"))


def test_a_failing_run_is_recorded_and_the_sweep_goes_on(tiny, tmp_path, capsys):
    ctrl = tmp_path / "raising.py"
    ctrl.write_text(RAISING)
    out = tmp_path / "sw"
    argv = [
        "sweep",
        "--suite",
        tiny,
        "--controllers",
        "oracle",
        f"{ctrl}:Raising",
        "--latency",
        "fixed:50",
        "--out",
        str(out),
    ]
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert "2 run(s) failed" in err and "Raising" in err
    import csv
    import json

    rows = list(csv.DictReader((out / "results.csv").open()))
    assert len(rows) == 4
    failed = [r for r in rows if r["error"]]
    assert len(failed) == 2 and all("always fails" in r["error"] for r in failed)
    assert all(r["folder"] for r in rows if r["controller"] == "oracle")
    failures = json.loads((out / "failures.json").read_text())
    assert len(failures) == 2 and all("RuntimeError" in v for v in failures.values())
    assert not [p for p in out.glob("runs/**/*") if p.name.endswith(".partial")]


@pytest.mark.slow  # a local Ray cluster starts a dozen processes: CI runs it with -m slow
def test_ray_backend_gives_the_local_results(tiny, tmp_path):
    pytest.importorskip("ray")
    s = _settings(tiny, controllers=("geofence", "oracle"), num_alphas=(1,))
    run_sweep(s, tmp_path / "local", workers=1, progress=False)
    outcome = run_sweep(s, tmp_path / "ray", workers=2, backend="ray", progress=False)
    assert not outcome.failed
    assert (tmp_path / "ray" / "results.csv").read_bytes() == (tmp_path / "local" / "results.csv").read_bytes()


def test_results_have_the_documented_columns(tiny, tmp_path):
    import csv

    run_sweep(_settings(tiny, controllers=("oracle",)), tmp_path / "sw", progress=False)
    header = next(csv.reader((tmp_path / "sw" / "results.csv").open()))
    for col in (
        "controller",
        "num_alphas",
        "thresholds_s",
        "latency_mode",
        "seed",
        "folder",
        "collision",
        "relative_impact_speed_kph",
        "ttc_at_first_warning_s",
        "false_alarm",
        "ncap_band",
        "error",
    ):
        assert col in header
    summary = next(csv.reader((tmp_path / "sw" / "summary.csv").open()))
    for col in (
        "controller",
        "num_alphas",
        "latency_mode",
        "threats_avoided",
        "threats",
        "fcw_pass_rate",
        "false_alarms",
        "latency_ms_mean",
        "latency_ms_p95",
        "frames_skipped_share",
    ):
        assert col in summary
    assert Path(tmp_path / "sw" / "report.html").stat().st_size > 1000


def test_the_fovea_is_a_dimension_of_camera_controllers_only(tiny):
    s = _settings(tiny, controllers=("geofence", "oracle"), num_alphas=(4,), foveas=(None, 4.0))
    plan = plan_runs(s, check_settings(s))
    # 2 cases x (geofence: 2 foveas + oracle: 1)
    assert len(plan) == 2 * 3 and len({p.run_id for p in plan}) == len(plan)
    assert {p.run_id.split("/")[0] for p in plan} == {
        "geofence-K4-fixed_50",
        "geofence-F4-K4-fixed_50",
        "oracle-fixed_50",
    }
    assert {p.fovea_zoom for p in plan if p.controller == "oracle"} == {None}
    with pytest.raises(ConfigError, match="foveas: fovea zoom 0.5"):
        check_settings(_settings(tiny, foveas=(0.5,)))


def test_a_fovea_sweep_reports_fovea_zoom_and_draws_the_latency_plot(tiny, tmp_path):
    import csv

    s = _settings(tiny, controllers=("flow",), num_alphas=(1, 2), foveas=(None, 2.0), latencies=("fixed:20",))
    run_sweep(s, tmp_path / "sw", progress=False)
    rows = list(csv.DictReader((tmp_path / "sw" / "results.csv").open()))
    assert {r["fovea_zoom"] for r in rows} == {"", "2.0"}
    summary = list(csv.DictReader((tmp_path / "sw" / "summary.csv").open()))
    assert len(summary) == 4 and {r["fovea_zoom"] for r in summary} == {"", "2.0"}
    assert "| flow | x2 | 1 |" in (tmp_path / "sw" / "summary.md").read_text()
    assert (tmp_path / "sw" / "plots" / "rates_vs_latency.png").stat().st_size > 1000
    assert "rates_vs_latency.png" in (tmp_path / "sw" / "report.html").read_text()


def test_cli_refuses_a_bad_fovea_before_any_run(tmp_path, capsys):
    out = tmp_path / "sw"
    argv = ["sweep", "--suite", "CCRs-20", "--controllers", "flow", "--fovea", "off", "x2", "--out", str(out)]
    assert main(argv) == 2
    assert "--fovea 'x2'" in capsys.readouterr().err and not out.exists()
