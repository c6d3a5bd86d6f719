"""The closed loop end to end: camera-fed runs, byte-identical outputs with fixed latency,
the controller interface, and every bad input of `bittc run` refused before anything is written."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

import controllers
import scenarios
from bittc_core.errors import ConfigError
from sim.camera import CameraConfig
from sim.cli import main
from sim.latency import parse_latency
from sim.runner import run_case

ROOT = Path(__file__).resolve().parents[1]


def test_camera_fed_run_with_fixed_latency_is_byte_identical(tmp_path):
    case = scenarios.resolve("CCRs-30")[0]
    ctrl = controllers.make("geofence", thresholds_s=(1.0, 2.0))  # built once, reset per run
    outs = []
    for i in range(2):
        d = tmp_path / f"r{i}"
        run_case(case, ctrl, CameraConfig(), seed=3, out_dir=d, latency=parse_latency("fixed:150"))
        outs.append(tuple((d / f).read_bytes() for f in ("trace.csv", "summary.json", "config.yaml")))
    assert outs[0] == outs[1]
    s = json.loads(outs[0][1])
    assert s["latency_mode"] == "fixed:150" and s["latency_ms_mean"] == 150.0 and s["frames_skipped"] > 0
    assert s["num_alphas"] == 2 and s["thresholds_s"] == [1.0, 2.0] and set(s["fence_lag_s"]) == {"1", "2"}
    # the car ahead is in view from the first job: seen at the TTC of the first pair, before any warning
    assert s["ttc_at_first_seen_s"] > max(s["ttc_at_first_warning_s"] or 0.0, 3.0)
    header = outs[0][0].decode().splitlines()[0].split(",")
    for col in ("frame", "latency_ms", "wait_ms", "inpath_px_1s", "fence_fired_s", "crit_inside_2s"):
        assert col in header


def test_a_network_driven_run_brakes_for_a_stationary_target(tmp_path):
    s = run_case(
        scenarios.resolve("CCRs-30")[0],
        controllers.make("geofence"),
        CameraConfig(),
        seed=0,
        latency=parse_latency("fixed:20"),
    )
    assert s["t_first_brake_s"] is not None and s["speed_reduction_kph"] > 15


def test_the_example_controller_runs(tmp_path):
    """As the README runs it: the file's path, from any directory."""
    out = tmp_path / "mine"
    example = ROOT / "examples" / "my_controller.py"
    r = subprocess.run(
        [
            sys.executable,
            "-m",
            "sim.cli",
            "run",
            "CCRs-30",
            "--controller",
            f"{example}:DistanceKeeper",
            "--latency",
            "fixed:20",
            "--out",
            str(out),
        ],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert r.returncode == 0, r.stderr
    s = json.loads((out / "summary.json").read_text())
    assert s["controller"] == "distance-keeper" and s["t_first_brake_s"] is not None


def test_make_refuses_unknown_settings_and_non_controllers():
    with pytest.raises(ConfigError, match="takes no setting 'thresholds_s'"):
        controllers.make("oracle", thresholds_s=(1.0,))
    with pytest.raises(ConfigError, match="not a subclass"):
        controllers.make("sim.latency:LatencyMode")


@pytest.mark.parametrize(
    "extra,needle",
    [
        (["--controller", "autopilot"], "unknown controller 'autopilot'"),
        (["--controller", "no_such_module:Thing"], "cannot import module 'no_such_module'"),
        (["--controller", "sim.latency:Nothing"], "has no attribute 'Nothing'"),
        (["--controller", "sim.latency:LatencyMode"], "not a subclass"),
        (["--controller", "no/such/file.py:Thing"], "no file 'no/such/file.py'"),
        (["--controller", "geofence", "--num-alphas", "0"], "--num-alphas"),
        (["--controller", "geofence", "--ttc-thresholds", "0"], "threshold 0.0 s"),
        (["--controller", "geofence", "--ttc-thresholds", "-1"], "threshold -1.0 s"),
        (["--controller", "geofence", "--ttc-thresholds", "nan"], "threshold nan s"),
        (["--controller", "geofence", "--ttc-thresholds", "1", "2", "1"], "given twice"),
        (["--controller", "geofence", "--latency", "fixed:x"], "fixed:MS"),
        (["--controller", "geofence", "--latency", "profile:toaster"], "unknown profile 'toaster'"),
        (["--controller", "geofence", "--latency", "sometimes"], "expected measured"),
        (["--controller", "geofence", "--fps", "1", "--num-alphas", "1"], "frame interval 3 s (1 s x stride 3)"),
        (["--controller", "geofence", "--frame-stride", "3", "--ttc-thresholds", "0.4"], "frame interval 0.3 s"),
        (["--controller", "oracle", "--num-alphas", "4"], "not 'oracle'"),
        (["--controller", "geofence", "--road-edge-rows", "-1"], "--road-edge-rows -1: must be an integer >= 0"),
        (["--controller", "oracle", "--road-edge-rows", "3"], "not 'oracle'"),
        (["--controller", "oracle", "--no-turn-across"], "--[no-]turn-across / --[no-]oncoming apply to"),
        (["--controller", "oracle", "--no-oncoming"], "--[no-]oncoming apply to"),
        (["--controller", "oracle", "--fovea-short-pair"], "--[no-]fovea-short-pair / --[no-]turn-across"),
    ],
)
def test_bad_input_is_refused_by_name_and_nothing_is_written(tmp_path, capsys, extra, needle):
    out = tmp_path / "out"
    assert main(["run", "CCRs-30", "--out", str(out), *extra]) == 2
    assert needle in capsys.readouterr().err
    assert not out.exists()


def test_a_fovea_run_is_byte_identical_and_reports_both_views(tmp_path):
    case = scenarios.resolve("CCRs-30")[0]
    ctrl = controllers.make("geofence", thresholds_s=(1.0, 2.0), fovea_fences_from_s=0.0)  # both fences in both views
    cam = CameraConfig(fovea_zoom=4.0)
    outs = []
    for i in range(2):
        d = tmp_path / f"r{i}"
        run_case(case, ctrl, cam, seed=3, out_dir=d, latency=parse_latency("fixed:20"))
        outs.append(tuple((d / f).read_bytes() for f in ("trace.csv", "summary.json", "config.yaml")))
    assert outs[0] == outs[1]
    s = json.loads(outs[0][1])
    assert s["fovea_zoom"] == 4.0 and s["frames_skipped"] == 0  # the frames before the first pair are not skips
    assert set(s["fence_lag_wide_s"]) == set(s["fence_lag_fovea_s"]) == set(s["fence_lag_persistent_s"]) == {"1", "2"}
    for k, lag in s["fence_lag_s"].items():  # the earlier cover of the two views
        views = [v for v in (s["fence_lag_wide_s"][k], s["fence_lag_fovea_s"][k]) if v is not None]
        assert lag == (min(views) if views else None)
    header = outs[0][0].decode().splitlines()[0].split(",")
    for col in ("inpath_px_1s", "inpath_px_fovea_1s", "fired_view", "crit_inside_2s", "crit_inside_fovea_2s"):
        assert col in header
    rows = outs[0][0].decode().splitlines()[1:]
    assert {r.split(",")[header.index("frame")] for r in rows} <= {"processed", "unpaired", "unused"}


def test_a_profile_charges_both_views_and_every_extraction(tmp_path):
    from sim.latency import JobWork, named_profiles

    prof = named_profiles()["this-cpu"]
    s = run_case(
        scenarios.resolve("CCRs-20")[0],
        controllers.make("geofence", thresholds_s=(1.0, 2.0)),  # the fovea runs the 2 s fence alone
        CameraConfig(fovea_zoom=2.0),
        seed=0,
        out_dir=tmp_path / "r",
        latency=parse_latency("profile:this-cpu"),
    )
    rows = (tmp_path / "r" / "trace.csv").read_text().splitlines()
    col = rows[0].split(",").index("latency_ms")
    lat = {float(r.split(",")[col]) for r in rows[1:] if r.split(",")[col]}
    # the fovea is half as wide: its thresholds and extractions count half (sim.cost_model.JobWork)
    steady = prof.latency_ms(JobWork("bittc", 2, 2 + 0.5, 1 + 0.5))  # one new frame per view
    first = prof.latency_ms(JobWork("bittc", 2, 2 + 0.5, 2 + 1))  # both frames of the first pairs, in both views
    assert lat == {round(steady, 2), round(first, 2)} and s["frames_skipped"] == 0
    # the flow baseline is priced by its own terms, not the network's
    flow = run_case(
        scenarios.resolve("CCRs-20")[0],
        controllers.make("flow", thresholds_s=(1.0, 2.0)),
        CameraConfig(),
        seed=0,
        latency=parse_latency("profile:this-cpu"),
    )
    assert flow["latency_ms_mean"] == pytest.approx(prof.latency_ms(JobWork("flow", 1, 2, 0)), abs=1e-3)


@pytest.mark.parametrize("bad", [0, 11, 2.5, True])
def test_the_frame_stride_has_one_bound_everywhere(bad):
    from controllers.geofence import GeofenceConfig, check_frame_stride
    from sim.env import ScenarioEnv

    with pytest.raises(ConfigError, match="frame stride"):
        check_frame_stride(bad)
    with pytest.raises(ConfigError, match="frame_stride"):
        GeofenceConfig(frame_stride=bad)
    with pytest.raises(ConfigError, match="frame stride"):
        ScenarioEnv("CCRs-30", frame_stride=bad)
