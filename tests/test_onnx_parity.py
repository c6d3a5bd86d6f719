"""The exported network against torch: pixel agreement, INT8 quantization's fence decisions
and its settings (skipped without the `onnx` extra; slow, as test_onnx.py)."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("onnx")
pytest.importorskip("onnxruntime")
pytest.importorskip("onnxscript")

from bittc_core.checkpoint import DEFAULT_WEIGHTS  # noqa: E402
from bittc_core.estimator import make_estimator  # noqa: E402
from bittc_core.export.manifest import ExportError  # noqa: E402
from bittc_core.export.onnx_export import export_onnx  # noqa: E402
from bittc_core.export.parity import Agreement  # noqa: E402
from tests.onnx_helpers import HALF, SIZE, tiny_checkpoint, zoom_pair  # noqa: E402

pytestmark = pytest.mark.slow


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


def test_int8_settings_need_pairs_of_every_size(tmp_path):
    from bittc_core.export.quantize import FramePairs, Int8Settings

    ckpt = tiny_checkpoint(tmp_path / "tiny.pt")
    a, b = zoom_pair(*SIZE, 0)
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
        a, b = zoom_pair(96, 288, seed)
        agr.add(ort.geofence(a, b, thr), ref.geofence(a, b, thr), ort.motion_in_depth(a, b), ref.motion_in_depth(a, b))
    r = agr.result()
    assert r["geofence_pixels_agreeing_min"] >= 0.999
    assert r["log_eta_abs_diff_p999"] <= 1e-3
