"""Estimator input validation, streaming cache, quantized maps, oracle and flow baseline."""

import numpy as np
import pytest
import torch

from bittc_core.data.synthetic import SyntheticConfig, SyntheticPairs
from bittc_core.estimator import BittcEstimator, EstimatorInputError, FlowEstimator, OracleEstimator, quantize
from bittc_core.model import BinaryTTCNet, get_config

H, W = 48, 96


@pytest.fixture(scope="module")
def est():
    torch.manual_seed(0)
    return BittcEstimator(BinaryTTCNet(get_config("tiny")), device=torch.device("cpu"))


def frame(seed):
    return np.random.default_rng(seed).integers(0, 256, (H, W, 3), dtype=np.uint8)


@pytest.mark.parametrize(
    "prev, latest, match",
    [
        (np.zeros((H, W, 3), np.uint8), np.zeros((H + 3, W, 3), np.uint8), "differ in size"),
        (np.zeros((H, W, 3), np.float32), np.zeros((H, W, 3), np.uint8), "dtype float32"),
        (np.zeros((H, W, 4), np.uint8), np.zeros((H, W, 4), np.uint8), r"\(48, 96, 4\)"),
        (torch.zeros(4, H, W), torch.zeros(4, H, W), r"\(4, 48, 96\)"),
        (torch.full((3, H, W), float("nan")), torch.zeros(3, H, W), "NaN"),
        (torch.zeros(3, H, W, dtype=torch.uint8), torch.zeros(3, H, W), "torch.uint8"),
        (torch.full((3, H, W), 2.0), torch.zeros(3, H, W), r"\[0, 1\]"),
        ("image.png", "image.png", "str"),
        (np.zeros((50, W, 3), np.uint8), np.zeros((50, W, 3), np.uint8), "multiples of 3"),
    ],
)
def test_bad_images(est, prev, latest, match):
    with pytest.raises(EstimatorInputError, match=match):
        est.geofence(prev, latest, [1.0])


@pytest.mark.parametrize(
    "thresholds, match",
    [
        ([], "empty"),
        ([1.0, -0.5], "-0.5"),
        ([0.0], "0.0"),
        ([float("nan")], "nan"),
        ([0.05], "0.05 s outside the trained range"),
        ([1.0, 50.0], "50 s outside the trained range"),
        ([[1.0, 2.0]], "1-D"),
        (["soon"], "not a list of numbers"),
    ],
)
def test_bad_thresholds(est, thresholds, match):
    with pytest.raises(EstimatorInputError, match=match):
        est.geofence(frame(0), frame(1), thresholds)


def test_errors_are_value_errors(est):
    with pytest.raises(ValueError):
        est.geofence(frame(0), frame(1), [])


def test_unsorted_thresholds_only_matter_for_quantized(est):
    p = est.geofence(frame(0), frame(1), [2.0, 0.5, 1.0])
    assert p.shape == (3, H, W) and p.dtype == np.float32 and ((p >= 0) & (p <= 1)).all()
    with pytest.raises(EstimatorInputError, match="2 s is followed by 0.5 s"):
        est.quantized(frame(0), frame(1), [2.0, 0.5, 1.0])
    with pytest.raises(EstimatorInputError, match="increase strictly"):
        est.quantized(frame(0), frame(1), [1.0, 1.0])


@pytest.mark.parametrize("stride", [1, 2, 3])
def test_a_strided_stream_extracts_every_frame_once(est, stride):
    """Pairs (f0, f_n), (f1, f_n+1), ...: the closed loop's strides up to its default."""
    est.reset()
    f = [frame(i) for i in range(6 + stride)]
    n0 = est.feature_computations
    for i in range(6):
        est.geofence(f[i], f[i + stride], [1.0])
    assert est.feature_computations - n0 == 6 + stride


def test_streaming_reuses_features_and_matches_uncached(est):
    est.reset()
    f = [frame(i) for i in range(4)]
    n0 = est.feature_computations
    outs = [est.geofence(f[i], f[i + 1], [0.5, 1.0, 3.0]) for i in range(3)]
    assert est.feature_computations - n0 == 4  # f0, f1, f2, f3: each extracted once
    est.geofence(f[2], f[3], [2.0])  # same pair, other thresholds: nothing new
    est.continuous(
        torch.from_numpy(f[2]).permute(2, 0, 1).float() / 255, torch.from_numpy(f[3]).permute(2, 0, 1).float() / 255
    )  # same pixels as tensors
    assert est.feature_computations - n0 == 4
    est.reset()
    fresh = est.geofence(f[1], f[2], [0.5, 1.0, 3.0])
    np.testing.assert_allclose(fresh, outs[1], atol=1e-6)
    # thresholds in any order give the same per-threshold maps
    swapped = est.geofence(f[1], f[2], [3.0, 0.5, 1.0])
    np.testing.assert_allclose(swapped, fresh[[2, 0, 1]], atol=1e-5)


def test_continuous_is_ttc_of_motion_in_depth(est):
    eta = est.motion_in_depth(frame(5), frame(6))
    tau = est.continuous(frame(5), frame(6))
    assert eta.shape == tau.shape == (H, W) and (eta > 0).all()
    np.testing.assert_allclose(tau, 0.1 * eta / (1 - eta), rtol=1e-4)


def _logit(p):
    return np.log(p) - np.log1p(-p)


def test_flip_averaging_is_the_mean_of_both_views_and_mirror_symmetric(est):
    flip = BittcEstimator(est.net, device=torch.device("cpu"), tta="flip")
    a, b = frame(7), frame(8)
    ma, mb = a[:, ::-1].copy(), b[:, ::-1].copy()
    thr = [0.5, 2.0]
    est.reset()
    plain, mirrored = est.geofence(a, b, thr), est.geofence(ma, mb, thr)[..., ::-1]
    expected = 1 / (1 + np.exp(-0.5 * (_logit(plain) + _logit(mirrored))))
    averaged = flip.geofence(a, b, thr)
    np.testing.assert_allclose(averaged, expected, atol=1e-6)
    assert np.abs(averaged - plain).max() > 1e-3  # the mirrored view changed something
    # the tolerance tells averaging logits from averaging probabilities
    assert np.abs(0.5 * (plain + mirrored) - expected).max() > 2e-6
    # the flip-averaged estimator commutes with mirroring the input
    np.testing.assert_allclose(flip.geofence(ma, mb, thr)[..., ::-1], averaged, atol=1e-6)
    eta_plain, eta_mirrored = est.motion_in_depth(a, b), est.motion_in_depth(ma, mb)[:, ::-1]
    eta = np.sqrt(eta_plain * eta_mirrored)  # the mean of log eta
    np.testing.assert_allclose(flip.motion_in_depth(a, b), eta, rtol=1e-6)
    assert np.abs(0.5 * (eta_plain + eta_mirrored) / eta - 1).max() > 2e-6
    with pytest.raises(AttributeError):
        flip.tta = "none"  # fixed at construction: the cache holds both views


def test_flip_averaging_streams(est):
    flip = BittcEstimator(est.net, device=torch.device("cpu"), tta="flip")
    f = [frame(20 + i) for i in range(3)]
    outs = [flip.geofence(f[i], f[i + 1], [1.0]) for i in range(2)]
    flip.continuous(f[1], f[2])
    assert flip.feature_computations == 3  # both views of a frame in one extraction
    flip.reset()
    np.testing.assert_allclose(flip.geofence(f[1], f[2], [1.0]), outs[1], atol=1e-6)


@pytest.mark.parametrize("tta", ["none", "flip"])
def test_a_repeated_pair_prepares_its_reference_once(est, tta, monkeypatch):
    e = BittcEstimator(est.net, device=torch.device("cpu"), tta=tta)
    calls = []
    prepare = e.net.prepare_reference
    monkeypatch.setattr(e.net, "prepare_reference", lambda *a: calls.append(1) or prepare(*a))
    a, b = frame(30), frame(31)
    e.geofence(a, b, [1.0])
    e.continuous(a, b)
    e.geofence(a, b.copy(), [2.0])
    assert len(calls) == 1 and e.feature_computations == 2


def test_bad_tta_mode(est):
    with pytest.raises(EstimatorInputError, match="tta='mirror'"):
        BittcEstimator(est.net, device=torch.device("cpu"), tta="mirror")
    from bittc_core.estimator import make_estimator

    with pytest.raises(EstimatorInputError, match="tta='flip' only applies to method 'bittc'"):
        make_estimator("flow", tta="flip")


def test_quantize_agrees_with_confident_binary_maps():
    rng = np.random.default_rng(0)
    k = 5
    # monotone-ish confident maps with random noise violations allowed
    raw = rng.uniform(0, 1, (k, 20, 30)).astype(np.float32)
    confident = np.where(raw > 0.5, rng.uniform(0.76, 1.0, raw.shape), rng.uniform(0.0, 0.24, raw.shape))
    q = quantize(confident.astype(np.float32))
    above = confident > 0.5
    first = np.where(above.any(axis=0), above.argmax(axis=0), k)  # first map saying "inside"
    np.testing.assert_array_equal(q, first)
    # exact binary maps of a known bin
    p = np.zeros((3, 1, 4), np.float32)
    p[:, 0, 1] = [0, 1, 1]
    p[:, 0, 2] = [1, 1, 1]
    p[:, 0, 3] = [0, 0, 1]
    np.testing.assert_array_equal(quantize(p)[0], [3, 1, 0, 2])


def test_oracle_is_exact_and_needs_ground_truth():
    oracle = OracleEstimator(dt_s=0.1)
    with pytest.raises(EstimatorInputError, match="set_ground_truth"):
        oracle.geofence(frame(0), frame(1), [1.0])
    eta = np.full((H, W), 0.95, np.float32)  # tau = 1.9 s
    eta[:, :10] = 1.2  # receding
    eta[:, 10:20] = 0.8  # tau = 0.4 s
    eta[0, 0] = np.nan
    oracle.set_ground_truth(torch.from_numpy(eta))
    p = oracle.geofence(frame(0), frame(1), [0.5, 2.0])
    assert p[0, :, 10:20].all() and not p[0, :, 20:].any() and not p[0, :, :10].any()
    assert p[1, :, 10:].all() and not p[1, :, :10].any()
    np.testing.assert_array_equal(oracle.quantized(frame(0), frame(1), [0.5, 2.0])[5], [2] * 10 + [0] * 10 + [1] * 76)
    np.testing.assert_allclose(oracle.continuous(frame(0), frame(1))[1, 30], 1.9, rtol=1e-5)
    oracle.set_ground_truth(np.ones((H + 3, W)))
    with pytest.raises(EstimatorInputError, match="does not match"):
        oracle.geofence(frame(0), frame(1), [1.0])


def test_oracle_auc_quantizes_eta_to_the_volume():
    from bittc_core.estimator import make_estimator

    oracle = OracleEstimator(dt_s=0.1, auc_volume=(0.6, 1.2, 24))  # maps at 0.6125, 0.6375, ...
    assert oracle.name == "oracle-auc"
    eta = np.full((H, W), 0.9, np.float32)
    eta[:, :10] = 0.91  # any eta in (0.8875, 0.9125], between two maps, comes out 0.9
    eta[:, 10:20] = 0.5  # below the volume: clamps to its lower end
    eta[:, 20:30] = 1.5  # above: clamps to the upper end
    oracle.set_ground_truth(eta)
    hat = oracle.motion_in_depth(frame(0), frame(1))
    np.testing.assert_allclose(hat[0, [0, 15, 25, 50]], [0.9, 0.6, 1.2, 0.9], atol=1e-6)
    p = oracle.geofence(frame(0), frame(1), [0.5, 2.0])  # the geofences stay exact
    assert p[1, :, :10].all() and not p[0, :, :10].any()
    with pytest.raises(EstimatorInputError, match="auc_volume"):
        OracleEstimator(auc_volume=(1.2, 0.6, 24))
    shipped = make_estimator("oracle-auc")
    assert shipped.auc_volume == (0.6, 1.2, 24)  # the shipped config's continuous volume


def test_flow_baseline_recovers_a_pure_expansion():
    cfg = SyntheticConfig(
        height_px=96, width_px=192, patches=(0, 0), background_eta=(0.9, 0.9), max_translation_px=0.0, noise_std=0.0
    )
    s = SyntheticPairs(1, cfg, seed=3)[0]
    flow = FlowEstimator()
    eta = flow.motion_in_depth(s["image_prev"], s["image_latest"])
    inner = eta[16:-16, 16:-16]
    assert abs(np.median(inner) - 0.9) < 0.02  # approaching plane: eta < 1, right direction
    g = flow.geofence(s["image_prev"], s["image_latest"], [0.5, 3.0])  # tau = 0.9 s
    assert g[0][16:-16, 16:-16].mean() < 0.2 and g[1][16:-16, 16:-16].mean() > 0.8


def test_dataset_evaluation_refuses_pairs_at_another_frame_interval():
    from bittc_core.dataset_eval import evaluate
    from bittc_core.errors import ConfigError

    oracle = OracleEstimator(dt_s=0.1)
    with pytest.raises(ConfigError, match=r"sample 0: dt_s=0.2 s but the estimator works at 0.1 s"):
        evaluate(oracle, [{"dt_s": 0.2}], limit=None)
