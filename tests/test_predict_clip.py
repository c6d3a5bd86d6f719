"""`bittc predict CLIP`: footage in (video or frames, timestamps, calibration), pairing, outputs, refusals."""

from __future__ import annotations

import csv
import json
import math

import cv2
import numpy as np
import pytest

from sim.cli import main
from sim.footage import FootageError, pair_frames, read_timestamps
from sim.footage_camera import Intrinsics, fovea_crop, read_kitti_calib, training_fovea_focal_px

FPS = 30.0
NATIVE_HW = (192, 576)  # [px] the test camera's frames
VFOV_DEG = 15.0  # narrow enough that a x4 fovea at 96 rows needs no upsampling (fy ~ 729 px)


@pytest.fixture(scope="module")
def clip(tmp_path_factory):
    """24 frames of CCRs-30 at 30 fps as PNG files, with timestamps and a KITTI calib file."""
    import scenarios
    from sim.camera import CameraConfig
    from sim.episode import ScenarioSim

    d = tmp_path_factory.mktemp("clip")
    (d / "frames").mkdir()
    cam = CameraConfig(height_px=NATIVE_HW[0], width_px=NATIVE_HW[1], vfov_deg=VFOV_DEG, fps_hz=FPS)
    sim = ScenarioSim(scenarios.resolve("CCRs-30")[0], cam, seed=0, render=True)
    frames = []
    try:
        sim.reset()
        for i in range(24):
            if i:
                for _ in range(sim.n_sub):
                    sim.substep(0.0)
            frames.append(sim.capture().image)
    finally:
        sim.close()
    for i, f in enumerate(frames):
        cv2.imwrite(str(d / "frames" / f"{i:06d}.png"), cv2.cvtColor(f, cv2.COLOR_RGB2BGR))
    (d / "timestamps.txt").write_text("".join(f"2011-09-26 13:02:25.{int(1e9 * i / FPS):09d}\n" for i in range(24)))
    fx, fy, cx, cy = cam.intrinsics()
    (d / "calib.txt").write_text(f"calib_time: x\nP_rect_02: {fx} 0 {cx} 0 0 {fy} {cy} 0 0 0 1 0\n")
    return d, frames, cam


def _rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def test_pairs_follow_the_network_interval_through_jitter_and_a_dropped_frame():
    t = np.arange(40) / 30.0
    assert (pair_frames(t, 0.1)[3:] == np.arange(37)).all() and (pair_frames(t, 0.1)[:3] == -1).all()
    assert (pair_frames(t, 0.3)[9:] == np.arange(31)).all()  # stride 3: 9 frames back
    ten = np.arange(20) * 0.1 + np.random.default_rng(0).uniform(-0.004, 0.004, 20)
    assert (pair_frames(ten, 0.1)[1:] == np.arange(19)).all()
    dropped = np.delete(np.arange(20) * 0.1, 10)  # frame at 1.0 s missing
    p = pair_frames(dropped, 0.1)
    assert p[10] == -1 and p[11] == 10 and p[9] == 8  # 1.1 s has no partner 0.1 s back
    with pytest.raises(FootageError, match="25 fps"):
        pair_frames(np.arange(30) / 25.0, 0.1)


def test_timestamps_read_kitti_dates_and_seconds_and_refuse_disorder(tmp_path):
    f = tmp_path / "t.txt"
    f.write_text("2011-09-26 13:02:25.964389445\n2011-09-26 13:02:26.068541198\n\n")
    assert np.allclose(read_timestamps(f), [0.0, 0.104151753], atol=1e-6)
    f.write_text("0.5\n0.6\n0.55\n")
    with pytest.raises(FootageError, match="out of order at frame 2"):
        read_timestamps(f)
    f.write_text("0.5\nnoon\n")
    with pytest.raises(FootageError, match="line 2"):
        read_timestamps(f)


def test_the_fovea_crop_spans_the_training_angle_per_pixel():
    kitti = Intrinsics(721.5377, 721.5377, 609.5593, 172.854)
    (u0, v0, u1, v1), (h, w) = fovea_crop((375, 1242), kitti, 4.0, (96, 288), pitch_deg=0.0)
    f_train, w_train = training_fovea_focal_px((96, 288), 4.0)
    assert (h, w) == (96, w_train) == (96, 144)
    assert abs((u1 - u0) / w - 721.5377 / f_train) < 0.01 and abs((v1 - v0) / h - 721.5377 / f_train) < 0.02
    assert abs((u0 + u1) / 2 - 0.5 - 609.56) <= 1 and abs((v0 + v1) / 2 - 0.5 - 172.85) <= 1
    fov = kitti.resized((v1 - v0, u1 - u0), (h, w), (u0, v0))
    assert abs(fov.fx_px - f_train) / f_train < 0.01  # the training fovea's focal length
    (_, v0p, _, _), _ = fovea_crop((375, 1242), kitti, 4.0, (96, 288), pitch_deg=2.0)
    assert v0p == v0 - round(721.5377 * math.tan(math.radians(2.0)))  # the horizon point moves up
    with pytest.raises(FootageError, match="upsampled"):
        fovea_crop((375, 1242), kitti, 8.0, (96, 288), 0.0)
    with pytest.raises(FootageError, match="larger than the"):
        fovea_crop((375, 1242), Intrinsics(4000, 4000, 600, 180), 4.0, (96, 288), 0.0)


def test_a_folder_of_frames_with_timestamps_and_the_controller(clip, tmp_path):
    d, frames, cam = clip
    out = tmp_path / "out"
    args = ["predict", str(d / "frames"), "--timestamps", str(d / "timestamps.txt"), "--calib", str(d / "calib.txt")]
    args += ["--size", "96x288", "--fovea", "4", "--pitch", str(cam.pitch_deg), "--controller", "geofence"]
    assert main([*args, "--ego-speed", str(30 / 3.6), "--out", str(out)]) == 0
    rows = _rows(out / "frames.csv")
    assert [int(r["frame"]) for r in rows] == list(range(9, 24))  # stride 3 at 30 fps: 9 frames back
    assert all(int(r["prev_frame"]) == int(r["frame"]) - 9 and abs(float(r["pair_dt_s"]) - 0.3) < 1e-3 for r in rows)
    assert {"stage", "warning", "decel_mps2", "wide_inside_0.8s", "fovea_inside_2.8s"} <= set(rows[0])
    assert "fovea_inside_0.8s" not in rows[0]  # the fovea runs the fences from 1.4 s on
    s = json.loads((out / "prediction.json").read_text())
    assert s["paired_frames"] == 15 and s["frame_stride"] == 3 and s["controller"]["persistence_jobs"] == 6
    assert s["views"]["fovea"]["size_hw"] == [96, 144] and s["views"]["wide"]["crop_box_px"] == [0, 0, 576, 192]
    cap = cv2.VideoCapture(str(out / "overlay.mp4"))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 15 and abs(cap.get(cv2.CAP_PROP_FPS) - FPS) < 0.1
    assert sorted(p.name for p in out.iterdir()) == ["frames.csv", "overlay.mp4", "prediction.json"]


def test_the_controller_takes_the_ego_motion_of_each_frame_from_oxts(clip, tmp_path, capsys):
    from sim.kitti_raw import oxts_line

    d, frames, cam = clip
    oxts = tmp_path / "oxts" / "data"
    oxts.mkdir(parents=True)
    speed = [30 / 3.6 - 0.05 * i for i in range(24)]  # braking: the speed of every frame differs
    for i, v in enumerate(speed):
        (oxts / f"{i:010d}.txt").write_text(oxts_line(v, 0.01 * i))
    args = ["predict", str(d / "frames"), "--timestamps", str(d / "timestamps.txt"), "--calib", str(d / "calib.txt")]
    args += ["--size", "96x288", "--fovea", "off", "--pitch", str(cam.pitch_deg), "--controller", "geofence"]
    out = tmp_path / "out"
    assert main([*args, "--oxts", str(oxts.parent), "--out", str(out)]) == 0
    rows = _rows(out / "frames.csv")
    assert [float(r["ego_speed_mps"]) for r in rows] == pytest.approx(speed[9:], abs=1e-4)
    assert [float(r["ego_yaw_rate_radps"]) for r in rows] == pytest.approx([0.01 * i for i in range(9, 24)], abs=1e-5)
    assert json.loads((out / "prediction.json").read_text())["controller"]["ego_motion"] == "oxts"
    (oxts / f"{23:010d}.txt").unlink()  # one frame without its oxts file
    bad = tmp_path / "bad"
    assert main([*args, "--oxts", str(oxts.parent), "--out", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "--oxts" in err and "23 oxts files for 24 frames" in err
    assert not bad.exists()


def test_a_video_at_its_own_frame_rate_with_a_region(clip, tmp_path):
    d, frames, _ = clip
    video = tmp_path / "clip.mp4"
    w = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"mp4v"), FPS, NATIVE_HW[::-1])
    for f in frames:
        w.write(cv2.cvtColor(f, cv2.COLOR_RGB2BGR))
    w.release()
    out = tmp_path / "out"
    roi = ["240", "60", "336", "150"]
    args = ["predict", str(video), "--size", "96x288", "--tau", "1", "2", "--frame-stride", "1", "--roi", *roi]
    assert main([*args, "--out", str(out)]) == 0
    rows = _rows(out / "frames.csv")
    assert [int(r["prev_frame"]) for r in rows] == list(range(0, 21))  # 0.1 s at 30 fps: 3 frames back
    assert {"wide_inside_1s", "wide_roi_inside_2s"} <= set(rows[0]) and "stage" not in rows[0]
    assert 0 <= float(rows[-1]["wide_roi_inside_2s"]) <= 1


def test_bad_footage_is_refused_and_nothing_is_written(clip, tmp_path, capsys):
    d, frames, _ = clip
    out = tmp_path / "out"
    one = tmp_path / "one"
    one.mkdir()
    cv2.imwrite(str(one / "0.png"), frames[0])
    bad_order = tmp_path / "t.txt"
    bad_order.write_text("".join(f"{t}\n" for t in [0, 0.1, 0.05] + [0.1 * i for i in range(3, 24)]))
    no_key = tmp_path / "calib.txt"
    no_key.write_text("P_rect_00: 1 0 0 0 0 1 0 0 0 0 1 0\n")
    base = ["--size", "96x288", "--out", str(out)]
    cases = {
        "1 frame(s)": ["predict", str(one), "--fps", "10", *base],
        "out of order at frame 2": ["predict", str(d / "frames"), "--timestamps", str(bad_order), *base],
        "no P_rect_02 key": ["predict", str(d / "frames"), "--fps", "30", "--calib", str(no_key), *base],
        "25 fps": ["predict", str(d / "frames"), "--fps", "25", "--frame-stride", "1", *base],
        "--ego-speed": ["predict", str(d / "frames"), "--fps", "30", "--controller", "geofence", *base],
        "apply to a clip": ["predict", str(one / "0.png"), str(one / "0.png"), "--fps", "30", *base],
    }
    for message, argv in cases.items():
        assert main(argv) == 2, message
        assert message in capsys.readouterr().err
        assert not out.exists() or not any(out.iterdir()), message


def test_kitti_calib_needs_twelve_numbers(tmp_path):
    f = tmp_path / "c.txt"
    f.write_text("P_rect_02: 1 0 2\n")
    with pytest.raises(FootageError, match="3 values"):
        read_kitti_calib(f)
