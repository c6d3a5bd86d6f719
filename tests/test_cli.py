"""The `bittc` CLI: outputs, exit codes, nothing half-written on bad input."""

import json
import os
import subprocess
import sys

import pytest

from sim.cli import main


def test_run_writes_documented_outputs(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["run", "CCRs-50", "--controller", "oracle", "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    for key in (
        "scenario",
        "controller",
        "threat",
        "collision",
        "impact_speed_kph",
        "relative_impact_speed_kph",
        "min_gap_m",
        "t_first_warning_s",
        "ttc_at_first_warning_s",
        "t_first_brake_s",
        "ttc_at_first_brake_s",
        "false_alarm",
        "steps",
        "sim_time_s",
        "num_alphas",
        "thresholds_s",
        "latency_mode",
        "latency_ms_mean",
        "latency_ms_p95",
        "frames_skipped",
    ):
        assert key in s
    header = (out / "trace.csv").read_text().splitlines()[0].split(",")
    for col in ("t_s", "ego_speed_kph", "critical_ttc_s", "warning", "brake_cmd_mps2", "gap_m_actor1"):
        assert col in header
    assert (out / "config.yaml").exists()
    assert sorted(p.name for p in out.iterdir()) == ["config.yaml", "summary.json", "timing.json", "trace.csv"]
    assert "wall_time_s" in json.loads((out / "timing.json").read_text())


def test_run_with_video(tmp_path):
    out = tmp_path / "v"
    assert main(["run", "CCRs-20", "--controller", "oracle", "--out", str(out), "--video"]) == 0
    assert (out / "camera.mp4").stat().st_size > 10_000
    assert not [p for p in out.iterdir() if p.name.startswith(".")]


@pytest.mark.parametrize(
    "argv,needle",
    [
        (["run", "CCRs-5", "--controller", "oracle"], "did you mean"),
        (["run", "CCRs-50", "--controller", "oracle", "--size", "96by288"], "--size"),
        (["run", "CCRs-50", "--controller", "oracle", "--seed", "-1"], "--seed -1"),
        (["run", "CCRs-50", "--controller", "oracle", "--fps", "0"], "--fps 0"),
        (["run", "CCRs-50", "--controller", "oracle", "--vehicle-texture", "chrome"], "--vehicle-texture 'chrome'"),
        (["suite", "--scenarios", "CCRs-50", "--ground-texture", "gravel"], "--ground-texture 'gravel'"),
    ],
)
def test_bad_flags_exit_2_and_write_nothing(tmp_path, capsys, argv, needle):
    out = tmp_path / "o"
    assert main([*argv, "--out", str(out)]) == 2
    assert needle in capsys.readouterr().err
    assert not out.exists() or not any(out.iterdir())


def test_unwritable_out(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert main(["run", "CCRs-50", "--controller", "oracle", "--out", str(blocker / "sub")]) == 2
    assert "--out" in capsys.readouterr().err


@pytest.mark.skipif(os.geteuid() == 0, reason="root can write anywhere")
def test_readonly_out(tmp_path, capsys):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    assert main(["run", "CCRs-50", "--controller", "oracle", "--out", str(ro)]) == 2


def test_console_script_lists_scenarios():
    r = subprocess.run([sys.executable, "-m", "sim.cli", "scenarios"], capture_output=True, text=True, check=True)
    assert "CCRs" in r.stdout and "benign-free-road" in r.stdout


def test_suite_table(tmp_path, capsys):
    assert main(["suite", "--out", str(tmp_path), "--scenarios", "CCRs-50,benign-receding"]) == 0
    out = capsys.readouterr().out
    assert "threats avoided: 1/1" in out and "false alarms: 0/1" in out
    assert "points: 1.0/1" in out and "mean impact of the rest" not in out  # avoided: no rest
    assert (tmp_path / "summary.csv").read_text().count("\n") == 3


def test_sweep_with_video_writes_one_video_per_case(tmp_path):
    assert main(["suite", "--out", str(tmp_path), "--scenarios", "CCRs-10,CCRs-20", "--video"]) == 0
    assert (tmp_path / "CCRs-10" / "camera.mp4").exists() and (tmp_path / "CCRs-20" / "camera.mp4").exists()


def test_seed_out_of_range(tmp_path, capsys):
    assert main(["run", "CCRs-50", "--controller", "oracle", "--out", str(tmp_path / "o"), "--seed", str(2**33)]) == 2
    assert "--seed" in capsys.readouterr().err
