"""ONNX export, the onnxruntime backend and its checks (skipped without the `onnx` extra).

All slow (`pytest -m slow`, which CI runs after the default tests): the exports themselves
take most of a minute (torch.onnx with dynamo), on one core under `-n 2`."""

from __future__ import annotations

import dataclasses
import json
import sys

import numpy as np
import pytest
import torch

pytest.importorskip("onnx")
pytest.importorskip("onnxruntime")
pytest.importorskip("onnxscript")

from bittc_core.checkpoint import DEFAULT_WEIGHTS, make_payload, save_checkpoint  # noqa: E402
from bittc_core.estimator import make_estimator  # noqa: E402
from bittc_core.export.manifest import FORMAT_ONE_SIZE, MANIFEST, ExportError, read_manifest  # noqa: E402
from bittc_core.export.onnx_export import export_onnx  # noqa: E402
from bittc_core.export.parity import Agreement  # noqa: E402
from bittc_core.model import BinaryTTCNet, get_config  # noqa: E402
from sim.cli import main  # noqa: E402

SIZE = (24, 48)  # (H, W) of the tiny network's test frames
HALF = (24, 24)  # (H, W) of a view half as wide (as the fovea beside the wide view)

pytestmark = pytest.mark.slow


def _tiny_checkpoint(path, seed: int = 0, shift_px: int = 0):
    torch.manual_seed(seed)
    # the correlation volume too (and its shifted correlations with ``shift_px``)
    cfg = dataclasses.replace(get_config("tiny"), corr_groups=4, corr_shift_px=shift_px)
    net = BinaryTTCNet(cfg).eval()
    if shift_px:  # the shifted correlations' convs start at zero: make them count
        with torch.no_grad():
            net.segnet.shift_first.weight.normal_(0.0, 0.3)
            net.segnet.shift_last.weight.normal_(0.0, 0.3)
    save_checkpoint(path, make_payload(net, "tiny", {"frame_dt_s": cfg.frame_dt_s}))
    return path


def _zoom_pair(h: int, w: int, seed: int, zoom: float = 1.05):
    """A smooth random texture and the same texture zoomed about the centre (approaching)."""
    import cv2

    rng = np.random.default_rng(seed)
    base = cv2.resize(rng.integers(0, 256, (h // 4 + 1, w // 4 + 1, 3), dtype=np.uint8), (w, h))
    m = cv2.getRotationMatrix2D(((w - 1) / 2, (h - 1) / 2), 0.0, zoom)
    return base, cv2.warpAffine(base, m, (w, h), borderMode=cv2.BORDER_REFLECT)


@pytest.fixture(scope="module")
def tiny_export(tmp_path_factory):
    d = tmp_path_factory.mktemp("tiny")
    ckpt = _tiny_checkpoint(d / "tiny.pt")
    export_onnx(ckpt, d / "onnx", sizes=[SIZE, HALF])
    return ckpt, d / "onnx"


def test_tiny_round_trip_matches_torch(tiny_export):
    ckpt, folder = tiny_export
    m = json.loads((folder / MANIFEST).read_text())
    assert m["format"] == "bittc-onnx/2" and m["precision"] == "float32" and m["quantization"] is None
    assert [(s["height_px"], s["width_px"]) for s in m["sizes"]] == [SIZE, HALF]
    graphs = m["sizes"][0]["graphs"]
    assert set(graphs) == {"extractor", "reference", "thresholds", "continuous"} and m["frame_dt_s"] == 0.1
    assert graphs["thresholds"]["file"] == "thresholds_24x48.onnx"
    assert m["sizes"][1]["graphs"]["thresholds"]["file"] == "thresholds_24x24.onnx"
    eta_in = next(i for i in graphs["thresholds"]["inputs"] if i["name"] == "eta")
    assert eta_in["shape"] == ["views", "thresholds"]
    ref = make_estimator("bittc", weights=str(ckpt), device="cpu")
    ort = make_estimator("bittc", weights=str(ckpt), backend="onnxruntime", onnx=str(folder))
    thr = [0.3, 0.9, 1.6, 2.4, 3.0, 4.0, 5.0, 6.0, 8.0, 9.5]  # 10 > one run of the thresholds graph
    for seed in range(3):
        a, b = _zoom_pair(*SIZE, seed)
        np.testing.assert_allclose(ort.geofence(a, b, thr), ref.geofence(a, b, thr), atol=2e-5)
        np.testing.assert_allclose(np.log(ort.motion_in_depth(a, b)), np.log(ref.motion_in_depth(a, b)), atol=1e-4)
    assert ort.feature_computations == 6  # the streaming cache: each frame extracted once


def test_shifted_correlations_export(tmp_path):
    """A network with the volume's shifted correlations exports and matches torch."""
    ckpt = _tiny_checkpoint(tmp_path / "shift.pt", seed=1, shift_px=1)
    export_onnx(ckpt, tmp_path / "onnx", sizes=[SIZE])
    ref = make_estimator("bittc", weights=str(ckpt), device="cpu")
    ort = make_estimator("bittc", weights=str(ckpt), backend="onnxruntime", onnx=str(tmp_path / "onnx"))
    a, b = _zoom_pair(*SIZE, 2)
    thr = [0.5, 1.0, 2.0]
    np.testing.assert_allclose(ort.geofence(a, b, thr), ref.geofence(a, b, thr), atol=2e-5)


def test_each_size_runs_its_own_graphs_and_forks_share_them(tiny_export):
    """A fork of another size (the fovea beside the wide view) runs the graphs of its size."""
    ckpt, folder = tiny_export
    ref = make_estimator("bittc", weights=str(ckpt), device="cpu")
    ort = make_estimator("bittc", weights=str(ckpt), backend="onnxruntime", onnx=str(folder))
    fovea = ort.fork()
    assert ort.sizes_px == (SIZE, HALF) and fovea.sessions is ort.sessions
    thr = [0.5, 1.0, 2.0]
    for est, size in ((ort, SIZE), (fovea, HALF), (ort, HALF)):
        a, b = _zoom_pair(*size, 3)
        np.testing.assert_allclose(est.geofence(a, b, thr), ref.geofence(a, b, thr), atol=2e-5)
        np.testing.assert_allclose(np.log(est.motion_in_depth(a, b)), np.log(ref.motion_in_depth(a, b)), atol=1e-4)


def test_a_one_size_folder_of_the_first_format_still_loads(tiny_export, tmp_path):
    import shutil

    ckpt, folder = tiny_export
    old = tmp_path / "old"
    shutil.copytree(folder, old)
    m = json.loads((old / MANIFEST).read_text())
    size = m.pop("sizes")[0]
    m["image"] |= {"height_px": size["height_px"], "width_px": size["width_px"]}
    m |= {"format": FORMAT_ONE_SIZE, "graphs": size["graphs"]}
    del m["precision"], m["quantization"]
    (old / MANIFEST).write_text(json.dumps(m))
    ort = make_estimator("bittc", weights=str(ckpt), backend="onnxruntime", onnx=str(old))
    assert ort.sizes_px == (SIZE,) and ort.precision == "float32"
    a, b = _zoom_pair(*SIZE, 1)
    assert ort.geofence(a, b, [1.0]).shape == (1, *SIZE)
    (old / MANIFEST).write_text(json.dumps(m | {"format": "bittc-onnx/0"}))
    with pytest.raises(ExportError, match=r"format 'bittc-onnx/0'.*export the weights again"):
        make_estimator("bittc", backend="onnxruntime", onnx=str(old))


def test_export_sizes_are_checked(tmp_path):
    ckpt = _tiny_checkpoint(tmp_path / "t.pt")
    for sizes, match in (([SIZE, SIZE], "given twice"), ([(24, 40)], "multiples of 3"), ([], "empty")):
        with pytest.raises(ExportError, match=match):
            export_onnx(ckpt, tmp_path / "out", sizes=sizes)
    with pytest.raises(ExportError, match="one way"):
        export_onnx(ckpt, tmp_path / "out", sizes=[SIZE], height_px=24)
    assert not (tmp_path / "out").exists()


def test_flip_averaging_matches_torch(tiny_export):
    ckpt, folder = tiny_export
    ref = make_estimator("bittc", weights=str(ckpt), device="cpu", tta="flip")
    ort = make_estimator("bittc", weights=str(ckpt), backend="onnxruntime", onnx=str(folder), tta="flip")
    a, b = _zoom_pair(*SIZE, 7)
    np.testing.assert_allclose(ort.geofence(a, b, [1.0, 2.0]), ref.geofence(a, b, [1.0, 2.0]), atol=2e-5)


def test_backend_input_checks_are_the_same(tiny_export):
    ckpt, folder = tiny_export
    ort = make_estimator("bittc", backend="onnxruntime", onnx=str(folder))
    a, b = _zoom_pair(*SIZE, 0)
    with pytest.raises(ValueError, match="outside the trained range"):
        ort.geofence(a, b, [50.0])
    with pytest.raises(ValueError, match="uint8"):
        ort.geofence(a.astype(np.float32), b, [1.0])
    big = np.zeros((48, 96, 3), np.uint8)
    with pytest.raises(ValueError, match=r"\(48, 96\) px.*takes \(24, 48\) or \(24, 24\) px"):
        ort.geofence(big, big, [1.0])


def test_export_of_other_weights_is_refused(tiny_export, tmp_path):
    ckpt, folder = tiny_export
    other = _tiny_checkpoint(tmp_path / "other.pt", seed=1)
    with pytest.raises(ExportError, match="other weights"):
        make_estimator("bittc", weights=str(other), backend="onnxruntime", onnx=str(folder))
    with pytest.raises(ExportError, match="config"):
        make_estimator("bittc", weights=str(DEFAULT_WEIGHTS), backend="onnxruntime", onnx=str(folder))


def test_missing_or_corrupt_files_are_named(tiny_export, tmp_path):
    import shutil

    _, folder = tiny_export
    bad = tmp_path / "bad"
    shutil.copytree(folder, bad)
    data = (bad / "thresholds_24x24.onnx").read_bytes()
    (bad / "thresholds_24x24.onnx").write_bytes(data[: len(data) // 2])
    with pytest.raises(ExportError, match="thresholds_24x24.onnx.*corrupt"):
        make_estimator("bittc", backend="onnxruntime", onnx=str(bad))
    (bad / "thresholds_24x24.onnx").unlink()
    with pytest.raises(ExportError, match="thresholds_24x24.onnx.*missing.*24x24 px"):
        read_manifest(bad, graphs=("thresholds",))
    (bad / MANIFEST).write_text("{not json")
    with pytest.raises(ExportError, match="not valid JSON"):
        read_manifest(bad, graphs=())
    with pytest.raises(ExportError, match="no such folder"):
        read_manifest(tmp_path / "nowhere", graphs=())


def test_export_refuses_a_foreign_folder_and_writes_nothing(tmp_path):
    ckpt = _tiny_checkpoint(tmp_path / "t.pt")
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("keep")
    with pytest.raises(ExportError, match="not an ONNX export folder"):
        export_onnx(ckpt, mine, height_px=SIZE[0], width_px=SIZE[1])
    assert [p.name for p in mine.iterdir()] == ["notes.txt"]
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".partial")]


def test_cli_says_how_to_install_onnxruntime(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "onnxruntime", None)
    a, b = _zoom_pair(96, 288, 0)
    import cv2

    cv2.imwrite(str(tmp_path / "a.png"), a)
    cv2.imwrite(str(tmp_path / "b.png"), b)
    argv = [
        "predict",
        str(tmp_path / "a.png"),
        str(tmp_path / "b.png"),
        "--backend",
        "onnxruntime",
        "--onnx",
        str(tmp_path),
        "--out",
        str(tmp_path / "out"),
    ]
    assert main(argv) == 2
    assert "pip install -e '.[onnx]'" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_agreement_counts_pixels_and_log_eta():
    agr = Agreement([1.0, 2.0])
    p = np.full((2, 2, 2), 0.9, np.float32)
    q = p.copy()
    q[1, 0, 0] = 0.1  # one pixel of four differs at 2 s
    eta = np.ones((2, 2), np.float32)
    agr.add(p, q, eta, eta * np.exp(2e-3))
    r = agr.result()
    assert r["geofence_pixels_agreeing"] == {"1": 1.0, "2": 0.75}
    assert r["log_eta_within_0.001"] == 0.0 and abs(r["log_eta_abs_diff_max"] - 2e-3) < 1e-6


def test_int8_export_keeps_the_fence_decisions_on_held_out_scenes(tmp_path):
    """The shipped weights quantized at the fovea's size, calibrated on two scenes: on two
    other scenes at most 1 % of the pixels change their fence decision against float32, at
    every default fence of the geofence controller (mapped to the pairs' interval)."""
    import scenarios
    from bittc_core.export.quantize import PARITY_TARGET, FramePairs, Int8Settings
    from controllers.geofence import DEFAULT_FRAME_STRIDE, default_thresholds, estimator_thresholds
    from sim.camera import CameraConfig
    from sim.frame_pairs import render_pairs

    camera = CameraConfig(fovea_zoom=4)
    fovea = camera.fovea()

    def pairs(*names):
        cases = [scenarios.resolve_suite(n)[0] for n in names]
        return FramePairs(
            tuple(p for c in cases for p in render_pairs(c, camera, 0, 4, DEFAULT_FRAME_STRIDE)["fovea"]), ""
        )

    ref = make_estimator("bittc", device="cpu")
    thr = estimator_thresholds(ref, default_thresholds(4), camera.dt_s, DEFAULT_FRAME_STRIDE)
    settings = Int8Settings(pairs("CCRs-50", "cut-in"), pairs("CCRs-30", "near-merge-45-15m"), tuple(thr))
    m = export_onnx(DEFAULT_WEIGHTS, tmp_path / "int8", sizes=[(fovea.height_px, fovea.width_px)], int8=settings)
    key = f"{fovea.height_px}x{fovea.width_px}"
    assert m["precision"] == "int8" and m["quantization"]["parity"]["pairs"] == {key: 8}
    assert m["sizes"][0]["graphs"]["thresholds"]["precision"] == "int8"
    changed = m["quantization"]["parity"]["decision_changed"][key]
    assert len(changed) == 4 and max(changed.values()) <= PARITY_TARGET == 0.01, changed
    assert not [p.name for p in (tmp_path / "int8").iterdir() if not p.name.endswith((".onnx", ".json"))]
    est = make_estimator("bittc", weights=str(DEFAULT_WEIGHTS), backend="onnxruntime", onnx=str(tmp_path / "int8"))
    assert est.precision == "int8" and est.sizes_px == ((fovea.height_px, fovea.width_px),)


def test_bench_times_several_export_folders_side_by_side(tiny_export, tmp_path, capsys):
    import shutil

    ckpt, folder = tiny_export
    copy = tmp_path / "copy"
    shutil.copytree(folder, copy)
    common = ["bench", "--backend", "onnxruntime", "--weights", str(ckpt), "--size", "24x48", "--calls", "1"]
    assert main([*common, "--onnx", str(folder), str(copy), "--graphs", "--threads", "1"]) == 0
    out = capsys.readouterr().out
    assert "onnxruntime-float32-copy ms" in out and "24x24    thresholds" in out
    assert main([*common, "--onnx", str(folder), str(copy), "--fovea", "off", "--threads", "1"]) == 0
    assert "onnxruntime-float32-onnx" in capsys.readouterr().out
    assert main([*common, "--onnx", str(folder), str(folder)]) == 2
    assert "given twice" in capsys.readouterr().err
    assert main([*common, "--graphs"]) == 2


def test_int8_settings_need_pairs_of_every_size(tiny_export, tmp_path):
    from bittc_core.export.quantize import FramePairs, Int8Settings

    ckpt, _ = tiny_export
    a, b = _zoom_pair(*SIZE, 0)
    only_one = FramePairs(((a, b),), "")
    with pytest.raises(ExportError, match="none of 24x24 px"):
        export_onnx(ckpt, tmp_path / "out", sizes=[SIZE, HALF], int8=Int8Settings(only_one, only_one, (1.0,)))
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
def test_shipped_weights_agree_on_zoom_pairs(tmp_path):
    """The shipped network: >= 99.9 % of geofence pixels and log eta within 1e-3 on
    synthetic approach pairs (the 64-test-pair figure: `bittc eval --backend onnxruntime`)."""
    export_onnx(DEFAULT_WEIGHTS, tmp_path / "onnx")
    ref = make_estimator("bittc", device="cpu")
    ort = make_estimator("bittc", weights=str(DEFAULT_WEIGHTS), backend="onnxruntime", onnx=str(tmp_path / "onnx"))
    thr = [0.5, 1.0, 2.0, 4.0]
    agr = Agreement(thr)
    for seed in range(4):
        a, b = _zoom_pair(96, 288, seed)
        agr.add(ort.geofence(a, b, thr), ref.geofence(a, b, thr), ort.motion_in_depth(a, b), ref.motion_in_depth(a, b))
    r = agr.result()
    assert r["geofence_pixels_agreeing_min"] >= 0.999
    assert r["log_eta_abs_diff_p999"] <= 1e-3
