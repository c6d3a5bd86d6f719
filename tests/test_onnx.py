"""ONNX export, the onnxruntime backend and its checks (skipped without the `onnx` extra;
the parity with torch and INT8: test_onnx_parity.py).

All slow (`pytest -m slow`, which CI runs after the default tests): the exports themselves
take most of a minute (torch.onnx with dynamo), on one core under `-n 2`."""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest

pytest.importorskip("onnx")
pytest.importorskip("onnxruntime")
pytest.importorskip("onnxscript")

from bittc_core.checkpoint import DEFAULT_WEIGHTS  # noqa: E402
from bittc_core.estimator import make_estimator  # noqa: E402
from bittc_core.export.manifest import FORMAT_ONE_SIZE, MANIFEST, ExportError, read_manifest  # noqa: E402
from bittc_core.export.onnx_export import export_onnx  # noqa: E402
from sim.cli import main  # noqa: E402
from tests.onnx_helpers import HALF, SIZE, tiny_checkpoint, zoom_pair  # noqa: E402

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def tiny_export(tmp_path_factory):
    d = tmp_path_factory.mktemp("tiny")
    ckpt = tiny_checkpoint(d / "tiny.pt")
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
        a, b = zoom_pair(*SIZE, seed)
        np.testing.assert_allclose(ort.geofence(a, b, thr), ref.geofence(a, b, thr), atol=2e-5)
        np.testing.assert_allclose(np.log(ort.motion_in_depth(a, b)), np.log(ref.motion_in_depth(a, b)), atol=1e-4)
    assert ort.feature_computations == 6  # the streaming cache: each frame extracted once


@pytest.mark.parametrize("shift_px, column, column_input", [(1, False, False), (0, True, False), (0, True, True)])
def test_shifted_and_column_correlations_export(tmp_path, shift_px, column, column_input):
    """A network with the volume's shifted or column correlations, or the source warped by
    columns as a second input, exports and matches torch."""
    ckpt = tiny_checkpoint(tmp_path / "shift.pt", seed=1, shift_px=shift_px, column=column, column_input=column_input)
    export_onnx(ckpt, tmp_path / "onnx", sizes=[SIZE])
    ref = make_estimator("bittc", weights=str(ckpt), device="cpu")
    ort = make_estimator("bittc", weights=str(ckpt), backend="onnxruntime", onnx=str(tmp_path / "onnx"))
    a, b = zoom_pair(*SIZE, 2)
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
        a, b = zoom_pair(*size, 3)
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
    a, b = zoom_pair(*SIZE, 1)
    assert ort.geofence(a, b, [1.0]).shape == (1, *SIZE)
    (old / MANIFEST).write_text(json.dumps(m | {"format": "bittc-onnx/0"}))
    with pytest.raises(ExportError, match=r"format 'bittc-onnx/0'.*export the weights again"):
        make_estimator("bittc", backend="onnxruntime", onnx=str(old))


def test_export_sizes_are_checked(tmp_path):
    ckpt = tiny_checkpoint(tmp_path / "t.pt")
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
    a, b = zoom_pair(*SIZE, 7)
    np.testing.assert_allclose(ort.geofence(a, b, [1.0, 2.0]), ref.geofence(a, b, [1.0, 2.0]), atol=2e-5)


def test_backend_input_checks_are_the_same(tiny_export):
    ckpt, folder = tiny_export
    ort = make_estimator("bittc", backend="onnxruntime", onnx=str(folder))
    a, b = zoom_pair(*SIZE, 0)
    with pytest.raises(ValueError, match="outside the trained range"):
        ort.geofence(a, b, [50.0])
    with pytest.raises(ValueError, match="uint8"):
        ort.geofence(a.astype(np.float32), b, [1.0])
    big = np.zeros((48, 96, 3), np.uint8)
    with pytest.raises(ValueError, match=r"\(48, 96\) px.*takes \(24, 48\) or \(24, 24\) px"):
        ort.geofence(big, big, [1.0])


def test_export_of_other_weights_is_refused(tiny_export, tmp_path):
    ckpt, folder = tiny_export
    other = tiny_checkpoint(tmp_path / "other.pt", seed=1)
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
    ckpt = tiny_checkpoint(tmp_path / "t.pt")
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("keep")
    with pytest.raises(ExportError, match="not an ONNX export folder"):
        export_onnx(ckpt, mine, height_px=SIZE[0], width_px=SIZE[1])
    assert [p.name for p in mine.iterdir()] == ["notes.txt"]
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".partial")]


def test_cli_says_how_to_install_onnxruntime(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "onnxruntime", None)
    a, b = zoom_pair(96, 288, 0)
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
