"""`bittc generate`: determinism across workers/backends, kill-and-resume, format, bad input."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import torch

from bittc_core.data.dataset import TTCDataset
from bittc_core.data.format import read_sample
from sim.cli import main
from sim.datagen.generate import GenerationConfig, generate

SMALL = GenerationConfig(seed=3, height_px=48, width_px=144)


def dataset_files(root: Path) -> dict[str, bytes]:
    """Every file under ``root``, hidden ones included."""
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


def test_same_bytes_in_every_file_whatever_the_worker_count(tmp_path):
    """The folder holds the dataset only (no lock, no timings), byte for byte the same
    whether one worker or two made it."""
    generate(tmp_path / "a", SMALL, "train", 6, workers=1, backend="local", progress=False)
    generate(tmp_path / "b", SMALL, "train", 6, workers=2, backend="local", progress=False)
    fa, fb = dataset_files(tmp_path / "a"), dataset_files(tmp_path / "b")
    assert sorted(fa) == sorted(fb)
    assert {name for name in fa if "/" not in name} == {"dataset_card.json", "generation.yaml", "manifest.jsonl"}
    assert len([name for name in fa if name.startswith("train/")]) == 6 * 4
    for name in fa:
        assert fa[name] == fb[name], name
    assert not [name for name in fa if name.endswith(".lock")]


@pytest.mark.slow  # a local Ray cluster starts a dozen processes: CI runs it with -m slow
def test_ray_backend_gives_the_same_bytes(tmp_path):
    pytest.importorskip("ray")
    generate(tmp_path / "a", SMALL, "train", 4, workers=1, backend="local", progress=False)
    generate(tmp_path / "r", SMALL, "train", 4, workers=2, backend="ray", progress=False)
    assert dataset_files(tmp_path / "a") == dataset_files(tmp_path / "r")


def test_killed_run_resumes_to_the_same_dataset(tmp_path, capsys):
    ref, killed = tmp_path / "ref", tmp_path / "killed"
    argv = ["--samples", "10", "--seed", "3", "--size", "48x144", "--no-progress"]
    generate(ref, SMALL, "train", 10, workers=1, backend="local", progress=False)
    proc = subprocess.Popen(
        [sys.executable, "-m", "sim.cli", "generate", "--out", str(killed), *argv],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    deadline = time.time() + 120
    while time.time() < deadline and len(list((killed / "train").glob("0*"))) < 3:
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    done = sorted(p.name for p in (killed / "train").glob("0*"))
    assert 3 <= len(done) < 10, done
    # a damaged sample must be found and regenerated on resume
    (killed / "train" / done[0] / "gt.npz").write_bytes(b"garbage")
    capsys.readouterr()
    assert main(["generate", "--out", str(killed), *argv]) == 0
    assert json.loads(capsys.readouterr().out)["damaged_regenerated"] == 1
    assert dataset_files(killed) == dataset_files(ref)  # card and manifest included
    assert not list((killed / "train").glob(".tmp-*"))
    card = json.loads((killed / "dataset_card.json").read_text())
    assert card["splits"]["train"]["samples"] == 10


@pytest.mark.parametrize("fovea_share", [0.0, 1.0])
def test_generated_ground_truth_meets_the_closed_forms(tmp_path, fovea_share):
    """The stored intrinsics are those of the view rendered (the fovea's for a fovea scene)."""
    from dataclasses import replace

    generate(tmp_path, replace(SMALL, fovea_share=fovea_share), "val", 3, workers=1, backend="local", progress=False)
    for d in sorted((tmp_path / "val").iterdir()):
        frames, gt, meta = read_sample(d)
        intr, dt = meta["intrinsics"], meta["dt_s"]
        fx, fy, cx, cy = intr["fx_px"], intr["fy_px"], intr["cx_px"], intr["cy_px"]
        c0, c1 = (np.array(f["cam_T_world"]) for f in meta["frames"])
        Z1, inst, valid = gt["depth_m"][0].astype(np.float64), gt["instance"][0], gt["valid"][0]
        H, W = Z1.shape
        v, u = np.mgrid[0:H, 0:W].astype(np.float64)
        P1 = np.stack([(u - cx) / fx * Z1, (v - cy) / fy * Z1, Z1, np.ones_like(Z1)], -1)
        # static points: only the camera moved between the two stored poses
        P0 = np.einsum("ij,hwj->hwi", c0 @ np.linalg.inv(c1), P1)
        m = valid & (inst == 0)
        np.testing.assert_allclose(gt["eta"][0][m], (Z1 / P0[..., 2])[m], rtol=1e-5)
        np.testing.assert_allclose(gt["flow_px"][0][..., 0][m], (u - (fx * P0[..., 0] / P0[..., 2] + cx))[m], atol=1e-3)
        # tau and eta agree: tau = dt * eta / (1 - eta) from the latest frame, i.e. eta = tau / (tau + dt)
        tau = gt["tau_s"][0][valid].astype(np.float64)
        finite = np.isfinite(tau)
        np.testing.assert_allclose(gt["eta"][0][valid][finite], (tau / (tau + dt))[finite], rtol=2e-6)
        assert frames[0].shape == (48, 144, 3) and frames[0].dtype == np.uint8


def test_dataset_tensors_have_documented_shapes_and_flip_consistently(tmp_path):
    generate(tmp_path, SMALL, "train", 2, workers=1, backend="local", progress=False)
    plain = TTCDataset(tmp_path, "train")[0]
    expect = {
        "image_prev": ((3, 48, 144), torch.float32),
        "image_latest": ((3, 48, 144), torch.float32),
        "eta": ((48, 144), torch.float32),
        "tau_s": ((48, 144), torch.float32),
        "flow_px": ((2, 48, 144), torch.float32),
        "valid": ((48, 144), torch.bool),
        "instance": ((48, 144), torch.int64),
        "actor_class": ((48, 144), torch.int64),
        "inpath": ((48, 144), torch.bool),
        "dt_s": ((), torch.float32),
        "intrinsics": ((4,), torch.float32),
        "ego_speed_mps": ((), torch.float32),
    }
    assert set(plain) == set(expect)
    for k, (shape, dtype) in expect.items():
        assert tuple(plain[k].shape) == shape and plain[k].dtype == dtype, k
    meta = json.loads((tmp_path / "train" / "000000" / "meta.json").read_text())
    assert float(plain["ego_speed_mps"]) == pytest.approx(meta["frames"][-1]["ego"]["speed_mps"])
    assert 0.0 <= plain["image_latest"].min() and plain["image_latest"].max() <= 1.0
    aug = TTCDataset(tmp_path, "train", augment=True, seed=1)
    for epoch in range(6):  # some epoch flips
        aug.set_epoch(epoch)
        s = aug[0]
        if torch.equal(s["eta"], plain["eta"].flip(-1)):
            assert torch.allclose(s["flow_px"][0], -plain["flow_px"][0].flip(-1))
            assert s["intrinsics"][2] == pytest.approx(143 - plain["intrinsics"][2])
            break
    else:
        pytest.fail("no horizontal flip in 6 epochs")
    crop = TTCDataset(tmp_path, "train", crop_hw=(32, 96))[0]
    assert crop["eta"].shape == (32, 96)
    assert crop["intrinsics"][2] == pytest.approx((96 - 1) / 2) and crop["intrinsics"][3] == pytest.approx((32 - 1) / 2)


@pytest.mark.parametrize(
    "argv,needle",
    [
        (["--samples", "0", "--seed", "1"], "--samples 0"),
        (["--samples", "-5", "--seed", "1"], "--samples -5"),
        (["--samples", "2", "--seed", "1", "--size", "96x"], "--size"),
        (["--samples", "2", "--seed", "1", "--backend", "spark"], "--backend: invalid choice: 'spark'"),
        (["--samples", "2", "--seed", "-1"], "--seed -1"),
        (["--samples", "2", "--seed", str(2**32)], "--seed 4294967296"),
        (["--samples", "2", "--seed", "1", "--workers", "0"], "--workers 0"),
        (["--samples", "2", "--seed", "1", "--clip-length", "1"], "--clip-length 1"),
        (["--samples", "2", "--seed", "1", "--ground-texture", "gravel"], "--ground-texture 'gravel'"),
        (["--samples", "2", "--seed", "1", "--vehicle-texture", "chrome"], "--vehicle-texture 'chrome'"),
        (["--samples", "2", "--seed", "1", "--ahead-share", "1.5"], "--ahead-share 1.5"),
        (["--samples", "2", "--seed", "1", "--fovea-share", "-0.1"], "--fovea-share -0.1"),
    ],
)
def test_bad_generate_flags(tmp_path, capsys, argv, needle):
    out = tmp_path / "d"
    try:
        rc = main(["generate", "--out", str(out), "--no-progress", *argv])
    except SystemExit as e:  # refused by argparse (choices)
        rc = e.code
    assert rc == 2
    assert needle in capsys.readouterr().err
    assert not out.exists()


def test_foreign_or_mismatched_dir_is_refused(tmp_path, capsys):
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("mine")
    assert main(["generate", "--out", str(foreign), "--samples", "1", "--seed", "1", "--no-progress"]) == 2
    assert "not a bittc dataset" in capsys.readouterr().err
    assert not (tmp_path / ".foreign.lock").exists()  # the refused run took its lock file with it
    ds = tmp_path / "ds"
    generate(ds, SMALL, "train", 1, workers=1, backend="local", progress=False)
    assert (
        main(["generate", "--out", str(ds), "--samples", "1", "--seed", "4", "--size", "48x144", "--no-progress"]) == 2
    )
    assert "seed = 3" in capsys.readouterr().err


def test_a_dataset_loses_the_lock_file_older_runs_left_inside(tmp_path):
    from bittc_core.parallel import LOCK_FILE

    ds = tmp_path / "ds"
    generate(ds, SMALL, "train", 1, workers=1, backend="local", progress=False)
    (ds / LOCK_FILE).write_text("123\n")
    generate(ds, SMALL, "train", 1, workers=1, backend="local", progress=False)
    assert not (ds / LOCK_FILE).exists()


@pytest.mark.parametrize(
    "key, old_value, flag, other",
    [
        ("ground_texture", "smooth", "--ground-texture", "detailed"),
        ("vehicle_texture", "plain", "--vehicle-texture", "detailed"),
        ("ahead_share", "0.0", "--ahead-share", "0.5"),
        ("fovea_share", "0.0", "--fovea-share", "0.5"),
    ],
)
def test_datasets_made_before_a_texture_option_count_as_its_old_style(tmp_path, capsys, key, old_value, flag, other):
    ds = tmp_path / "ds"
    shown = float(old_value) if key.endswith("_share") else old_value
    old = GenerationConfig(seed=3, height_px=48, width_px=144, **{key: shown})
    generate(ds, old, "train", 1, workers=1, backend="local", progress=False)
    gen = ds / "generation.yaml"
    gen.write_text("".join(line for line in gen.read_text().splitlines(True) if not line.startswith(key)))
    common = ["generate", "--out", str(ds), "--samples", "2", "--seed", "3", "--size", "48x144", "--no-progress"]
    assert main([*common, flag, other]) == 2
    assert f"{key} = {shown!r}" in capsys.readouterr().err
    assert main([*common, flag, old_value]) == 0
    assert (ds / "train" / "000001" / "meta.json").exists()


def test_ray_missing_gives_a_clear_error(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)
    assert main(["generate", "--out", str(tmp_path / "d"), "--samples", "1", "--seed", "1", "--backend", "ray"]) == 2
    assert "pip install 'bittc-sim[ray]'" in capsys.readouterr().err


def test_data_stats_match_the_card(tmp_path, capsys):
    generate(tmp_path, SMALL, "val", 2, workers=1, backend="local", progress=False)
    assert main(["data", "stats", str(tmp_path), "--json"]) == 0
    stats = json.loads(capsys.readouterr().out)
    card = json.loads((tmp_path / "dataset_card.json").read_text())
    assert stats["splits"]["val"]["samples"] == 2
    assert stats["tau_histogram_actor_px"] == card["tau_histogram_actor_px"]
    manifest = [json.loads(line) for line in (tmp_path / "manifest.jsonl").read_text().splitlines()]
    assert [m["seed"] for m in manifest] == [1_000_000_000, 1_000_000_001]


def test_steady_rate_is_reported_only_over_a_long_enough_window(tmp_path):
    from sim.datagen.generate import steady_rate

    # 24 samples on 2 workers in chunks of 4: after each worker's first chunk the other
    # 16 results arrive in one burst, a window of almost no time
    assert steady_rate([2.0 + 1e-6 * i for i in range(24)], skip=8) is None
    assert steady_rate([1.0 + 0.05 * i for i in range(8)] + [3.0 + 0.05 * i for i in range(12)], skip=8) is None
    # 200 samples at a steady 20 samples/s
    assert steady_rate([1.0 + 0.05 * i for i in range(200)], skip=8) == pytest.approx(20.0)
    run = generate(tmp_path / "a", SMALL, "train", 6, workers=1, backend="local", progress=False)
    assert run["written"] == 6 and "steady_samples_per_s" in run and run["steady_samples_per_s"] is None
