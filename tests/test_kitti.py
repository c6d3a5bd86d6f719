"""The KITTI raw export of a run, the lidar truth read back from it, and `bittc eval --kitti-raw`."""

from __future__ import annotations

import csv
import json
import shutil

import numpy as np
import pytest

from sim.cli import main
from sim.footage import FootageError
from sim.kitti_eval import lidar_truth
from sim.kitti_raw import read_drive
from sim.lidar_lead import fit_ttc

CASE = """name: kitti-short
threat: true
duration_s: 2
ego: {speed_kph: 50}
actors:
  - {vehicle: car, lane: 0, speed_kph: 0, overlap_pct: 100, headway_m: 30}
"""


@pytest.fixture(scope="module")
def drive(tmp_path_factory):
    d = tmp_path_factory.mktemp("kitti")
    (d / "case.yaml").write_text(CASE)
    argv = ["run", str(d / "case.yaml"), "--controller", "none", "--out", str(d / "run")]
    assert main([*argv, "--export-kitti", str(d / "drive")]) == 0
    return d / "drive"


def _exported_ttc(folder):
    rows = list(csv.DictReader((folder / "bittc_truth.csv").open()))
    return np.array([float(r["critical_ttc_s"]) if r["critical_ttc_s"] else np.nan for r in rows])


def test_the_export_has_the_kitti_layout_and_its_lidar_gives_the_exact_ttc(drive):
    d = read_drive(drive)
    n = len(d.times_s)
    assert n == 20 and len(d.image_paths) == len(d.velo_paths) == n and np.allclose(np.diff(d.times_s), 0.1)
    assert d.intrinsics[2:] == (620.5, 187.0) and np.allclose(d.ego_speed_mps, 50 / 3.6, atol=1e-3)
    import cv2

    assert cv2.imread(str(d.image_paths[0])).shape == (375, 1242, 3)
    scan = d.scan(0)
    assert scan.dtype == np.float32 and scan.shape[1] == 4 and len(scan) > 5000
    leads, tau = lidar_truth(d)
    exact = _exported_ttc(drive)
    seen = np.isfinite(exact) & (exact < 4)
    assert seen.sum() >= 15
    assert np.nanmax(np.abs(tau[seen] / exact[seen] - 1)) < 0.05  # the target; it is far closer
    # the face's points project onto the target in the image
    u = leads[10].face_cam @ d.P_rect[:3, :3].T
    uv = u[:, :2] / u[:, 2:]
    assert abs(np.median(uv[:, 0]) - 620.5) < 40


def test_fit_ttc_is_exact_under_braking_and_stops_at_contact():
    t = np.arange(30) * 0.1
    depth = 40.0 - 12.0 * t + 0.5 * 3.0 * t**2  # closing at 12 m/s, slowing by 3 m/s^2
    tau = fit_ttc(t, depth)
    speed = 12.0 - 3.0 * t
    assert np.allclose(tau[3:-3], (depth / speed)[3:-3], rtol=1e-6)
    stop = np.concatenate([20.0 - 10.0 * t[:15], np.full(15, 5.9)])  # contact just after frame 14
    tau = fit_ttc(t, stop)
    assert np.allclose(tau[:15], (stop / 10.0)[:15], rtol=1e-6) and np.isinf(tau[20])


@pytest.mark.slow  # both estimators over a rendered drive: about 45 s; CI runs it with -m slow
def test_eval_kitti_raw_scores_both_estimators_and_checks_the_export(drive, tmp_path, capsys):
    out = tmp_path / "flow.json"
    argv = ["eval", "--kitti-raw", str(drive), "--method", "flow", "--strides", "1", "3", "--out", str(out)]
    assert main(argv) == 0
    r = json.loads(out.read_text())
    assert r["pairs"] > 20 and set(r["thresholds"]) == {"0.9", "1.6", "2.4"} and r["strides"] == [1, 3]
    assert r["lidar_truth_vs_export"]["relative_error_max"] < 0.05
    assert 0 <= r["thresholds"]["2.4"]["accuracy"] <= 1
    assert r["thresholds"]["0.9"]["road_false_fence_share"] is not None  # road beyond 12.5 m lies outside 0.9 s
    rows = list(csv.DictReader(out.with_suffix(".pairs.csv").open()))
    assert {int(x["stride"]) for x in rows} == {1, 3}
    k3 = next(x for x in rows if x["stride"] == "3")
    assert abs(float(k3["tau_eff_s"]) - float(k3["tau_s"]) / 3) < 1e-3  # time compression: tau / k at 10 Hz
    assert "continuous" in r and r["continuous"]["pairs"] > 0
    argv = ["eval", "--kitti-raw", str(drive), "--method", "bittc", "--strides", "1", "--out", str(tmp_path / "b.json")]
    assert main(argv) == 0 and json.loads((tmp_path / "b.json").read_text())["pairs"] > 10


def test_bad_drives_are_refused_by_name_and_nothing_is_written(drive, tmp_path, capsys):
    cases = {}
    short = tmp_path / "short_bin"
    shutil.copytree(drive, short)
    (short / "velodyne_points/data/0000000003.bin").write_bytes(b"\0" * 10)
    cases[short] = "0000000003.bin"
    nokey = tmp_path / "no_key"
    shutil.copytree(drive, nokey)
    (nokey / "calib_velo_to_cam.txt").write_text("R: 1 0 0 0 1 0 0 0 1\n")
    cases[nokey] = "no T key"
    order = tmp_path / "order"
    shutil.copytree(drive, order)
    lines = (order / "image_02/timestamps.txt").read_text().splitlines()
    lines[2], lines[3] = lines[3], lines[2]
    (order / "image_02/timestamps.txt").write_text("\n".join(lines) + "\n")
    cases[order] = "out of order at frame 3"
    for folder, message in cases.items():
        out = tmp_path / f"{folder.name}.json"
        assert main(["eval", "--kitti-raw", str(folder), "--method", "flow", "--out", str(out)]) == 2
        assert message in capsys.readouterr().err
        assert not out.exists() and not out.with_suffix(".pairs.csv").exists()
    with pytest.raises(FootageError, match="0000000003.bin"):
        read_drive(short)


def test_export_refuses_a_non_empty_folder_and_several_cases(drive, tmp_path, capsys):
    assert main(["run", "CCRs", "--controller", "none", "--out", str(tmp_path / "r"), "--export-kitti", "x"]) == 2
    assert "exports one case" in capsys.readouterr().err
    argv = ["run", "CCRs-50", "--controller", "none", "--out", str(tmp_path / "r"), "--export-kitti", str(drive)]
    assert main(argv) == 2 and "not an empty folder" in capsys.readouterr().err


def test_the_export_goes_through_the_runs_sensor_and_keeps_its_lidar_and_truth(drive, tmp_path):
    import cv2

    (tmp_path / "case.yaml").write_text(CASE.replace("duration_s: 2", "duration_s: 0.5"))
    argv = ["run", str(tmp_path / "case.yaml"), "--controller", "none", "--out", str(tmp_path / "run"), "--realism"]
    assert main([*argv, "--export-kitti", str(tmp_path / "drive")]) == 0
    sensed, clean = read_drive(tmp_path / "drive"), read_drive(drive)
    assert len(sensed.times_s) == 5
    for i in range(5):
        a = cv2.imread(str(sensed.image_paths[i])).astype(int)
        b = cv2.imread(str(clean.image_paths[i])).astype(int)
        assert a.shape == b.shape and 1.0 < np.abs(a - b).mean() < 60.0  # the same scene, through a sensor
        assert np.array_equal(sensed.scan(i), clean.scan(i))  # the lidar sees the exact surface either way
    truth = (tmp_path / "drive" / "bittc_truth.csv").read_text().splitlines()
    assert truth == (drive / "bittc_truth.csv").read_text().splitlines()[: len(truth)]


def test_the_export_leaves_the_runs_own_images_as_they_were(tmp_path):
    """The export draws its sensor noise and codes its video on streams of its own: the
    frames the controller sees through the same sensor are the same bytes with or without it."""
    import hashlib

    import scenarios
    from controllers.base import BrakeCommand, Controller
    from sim.camera import CameraConfig
    from sim.latency import parse_latency
    from sim.runner import run_case
    from sim.sensor import REALISM_STREAM, RUN_EFFECTS_WORD, draw_effects

    class Seen(Controller):
        name = "seen"
        needs_camera = True
        estimator_kind = "flow"
        num_alphas = 1

        def __init__(self):
            self.digests = []

        def act(self, obs, truth):
            self.digests.append(hashlib.sha1(obs.image_latest.tobytes() + obs.image_prev.tobytes()).hexdigest())
            return BrakeCommand(decel_mps2=0.0, warning=False)

    (tmp_path / "case.yaml").write_text(CASE.replace("duration_s: 2", "duration_s: 0.6"))
    case = scenarios.resolve(str(tmp_path / "case.yaml"))[0]
    sensor = draw_effects(np.random.default_rng([2, REALISM_STREAM, RUN_EFFECTS_WORD]))  # video coded, blurred
    assert sensor.video_qp is not None and sensor.exposure_s > 0
    seen = []
    for export in (None, tmp_path / "drive"):
        ctrl = Seen()
        kw = {"latency": parse_latency("fixed:0"), "sensor": sensor, "export_kitti": export}
        run_case(case, ctrl, CameraConfig(), 2, **kw)
        seen.append(ctrl.digests)
    assert len(seen[0]) >= 3 and seen[0] == seen[1]
    assert len(read_drive(tmp_path / "drive").times_s) == 6
