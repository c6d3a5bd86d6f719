"""The sensor model: each effect does what it says, deterministically, in the generator and the closed loop."""

from __future__ import annotations

import json

import numpy as np
import pytest
import yaml

from sim.sensor import SensorEffects, apply_effects, draw_effects


def _edge(h=24, w=48):
    img = np.zeros((h, w, 3), np.uint8)
    img[:, w // 2 :] = 200
    return img


def test_no_effects_give_the_same_bytes_and_a_draw_is_deterministic():
    rng = np.random.default_rng(0)
    img = rng.integers(0, 256, (16, 32, 3), dtype=np.uint8)
    assert np.array_equal(apply_effects(img, SensorEffects(), None, 0.1, rng), img)
    e = draw_effects(np.random.default_rng(3))
    assert e == draw_effects(np.random.default_rng(3))
    flow = np.full((16, 32, 2), 2.0, np.float32)
    a = apply_effects(img, e, flow, 0.1, np.random.default_rng(1))
    b = apply_effects(img, e, flow, 0.1, np.random.default_rng(1))
    assert np.array_equal(a, b) and not np.array_equal(a, img)


def test_motion_blur_spreads_a_moving_edge_and_the_rolling_shutter_shears_it():
    img = _edge()
    flow = np.zeros((24, 48, 2), np.float32)
    flow[..., 0] = 8.0  # 8 px per 0.1 s to the right
    blurred = apply_effects(img, SensorEffects(exposure_s=0.05), flow, 0.1, np.random.default_rng(0))
    row = blurred[10, :, 0].astype(int)
    ramp = np.flatnonzero((row > 10) & (row < 190))
    assert (
        2 <= len(ramp) <= 5 and ramp.max() <= 24
    )  # 4 px of motion over the exposure, behind the edge (it moved right)
    sheared = apply_effects(img, SensorEffects(readout_s=0.05), flow, 0.1, np.random.default_rng(0))
    first = [int(np.argmax(sheared[r, :, 0] > 100)) for r in (0, 23)]
    assert first[0] < 24 < first[1]  # the top row read early (the edge not yet there), the bottom late


def test_vignetting_darkens_the_corners_and_noise_grows_with_the_signal():
    flat = np.full((32, 64, 3), 180, np.uint8)
    v = apply_effects(flat, SensorEffects(vignetting=0.4), None, 0.1, np.random.default_rng(0))
    assert v[16, 32, 0] == 180 and v[0, 0, 0] < 150
    rng = np.random.default_rng(0)
    dark = apply_effects(np.full((64, 64, 3), 20, np.uint8), SensorEffects(full_well=300.0), None, 0.1, rng)
    bright = apply_effects(np.full((64, 64, 3), 230, np.uint8), SensorEffects(full_well=300.0), None, 0.1, rng)
    linear = [((x / 255.0) ** 2.2).std() for x in (dark, bright)]  # shot noise grows with the irradiance
    assert linear[1] > linear[0] > 0
    with pytest.raises(ValueError, match="vignetting"):
        SensorEffects(vignetting=1.5)


def test_the_generator_draws_a_sensor_per_clip_and_leaves_share_zero_as_it_was(tmp_path):
    from sim.cli import main

    assert main(["generate", "--out", str(tmp_path / "r"), "--split", "val", "--samples", "2", "--seed", "0",
                 "--realism-share", "1"]) == 0  # fmt: skip
    assert main(["generate", "--out", str(tmp_path / "c"), "--split", "val", "--samples", "2", "--seed", "0"]) == 0
    metas = [json.loads((tmp_path / "r/val" / f"{i:06d}/meta.json").read_text()) for i in range(2)]
    assert all(m["sensor"]["gain"] > 0 for m in metas) and metas[0]["sensor"] != metas[1]["sensor"]
    assert yaml.safe_load((tmp_path / "r/generation.yaml").read_text())["realism_share"] == 1.0
    clean = json.loads((tmp_path / "c/val/000000/meta.json").read_text())
    assert "sensor" not in clean and "realism_share" not in (tmp_path / "c/generation.yaml").read_text()
    # the same scene: the ground truth is the renderer's either way
    assert (tmp_path / "r/val/000000/gt.npz").read_bytes() == (tmp_path / "c/val/000000/gt.npz").read_bytes()
    assert (tmp_path / "r/val/000000/frame_1.png").read_bytes() != (tmp_path / "c/val/000000/frame_1.png").read_bytes()


def test_a_run_through_a_sensor_changes_the_images_only():
    import scenarios
    from sim.camera import CameraConfig
    from sim.episode import ScenarioSim

    case = scenarios.resolve("CCRs-30")[0]
    cam = CameraConfig(fovea_zoom=4)
    frames = {}
    for name, sensor in (("clean", None), ("sensor", draw_effects(np.random.default_rng(2)))):
        sim = ScenarioSim(case, cam, 0, render=True, sensor=sensor)
        try:
            sim.reset()
            out = [sim.capture()]
            for _ in range(sim.n_sub):
                sim.substep(0.0)
            out.append(sim.capture())
        finally:
            sim.close()
        frames[name] = out
    a, b = frames["clean"][1], frames["sensor"][1]
    assert np.array_equal(a.depth_m, b.depth_m) and np.array_equal(a.instance, b.instance)
    assert not np.array_equal(a.image, b.image) and not np.array_equal(a.fovea.rgb, b.fovea.rgb)
    assert a.image.shape == b.image.shape and b.fovea.rgb.shape == a.fovea.rgb.shape


def test_a_run_through_the_sensor_records_its_draw_in_config_yaml(tmp_path, capsys):
    from sim.cli import main

    for flags, d in ((["--realism"], "r"), ([], "c")):
        args = ["run", "CCRs-50", "--controller", "oracle", "--seed", "1", "--out", str(tmp_path / d)]
        assert main(args + flags) == 0
    printed = json.loads(capsys.readouterr().out.split("sensor: ", 1)[1].splitlines()[0])
    assert yaml.safe_load((tmp_path / "r/config.yaml").read_text())["sensor"] == printed
    assert yaml.safe_load((tmp_path / "c/config.yaml").read_text())["sensor"] is None
