"""Metrics on hand-made maps with known IoU, MiD and error rates."""

import math

import numpy as np
import pytest

from bittc_core.metrics import (
    MetricAccumulator,
    class_counts,
    inside_share_group,
    mid_terms,
    miou_thresholds_s,
    threshold_key,
    two_class_iou,
)
from bittc_core.ttc import eta_to_tau, tau_to_eta


def test_two_class_iou_known_values():
    truth = np.array([[1, 1, 0, 0]], bool)
    pred = np.array([[1, 0, 0, 0]], bool)
    valid = np.ones_like(truth)
    # inside: I=1, U=2 -> 0.5; outside: I=2, U=3 -> 2/3
    assert two_class_iou(class_counts(pred, truth, valid)) == pytest.approx((0.5 + 2 / 3) / 2)
    # the invalid pixel is ignored: inside 1/1, outside 2/2
    valid[0, 1] = False
    assert two_class_iou(class_counts(pred, truth, valid)) == pytest.approx(1.0)
    # a class absent from truth and prediction is skipped, not counted as 0 or 1
    none = np.zeros_like(truth)
    assert two_class_iou(class_counts(none, none, np.ones_like(truth))) == pytest.approx(1.0)
    assert math.isnan(two_class_iou(class_counts(pred, truth, np.zeros_like(truth))))


def test_miou_thresholds_span_the_table1_range_uniformly_in_eta():
    taus = miou_thresholds_s(0.1)
    assert taus[0] == pytest.approx(0.2) and taus[-1] == pytest.approx(2.0)
    assert np.allclose(np.diff(tau_to_eta(taus, 0.1)), np.diff(tau_to_eta(taus, 0.1))[0])


def test_mid_known_value():
    eta = np.array([[0.9, 1.0, 1.1, 3.0]])
    eta_hat = eta * np.exp([[0.01, -0.02, 0.0, 5.0]])  # the last pixel has |log eta| > log 2
    s, n = mid_terms(eta_hat, eta, np.ones_like(eta, bool))
    assert n == 3 and s / n * 1e4 == pytest.approx(100.0)


def test_accumulator_perfect_and_inverted_predictions():
    dt = 0.1
    eta = np.full((4, 6), 0.99)  # tau = 9.9 s: outside every metric geofence
    eta[:, :2] = tau_to_eta(0.5, dt)  # actor at 0.5 s
    eta[:, 2] = tau_to_eta(1.5, dt)
    instance = np.zeros(eta.shape, np.int64)
    instance[:, :3] = 1
    valid = np.ones(eta.shape, bool)
    acc = MetricAccumulator(dt_s=dt)
    truth = np.stack([(eta > 0) & (eta <= tau_to_eta(t, dt)) for t in acc.thresholds_s]).astype(np.float32)
    acc.add(truth, eta, eta, valid, instance, latency_ms=4.0)
    r = acc.result()
    assert r["miou"] == pytest.approx(1.0) and r["mid"] == pytest.approx(0.0)
    assert r["error_rate"] == {"1": 0.0, "2": 0.0, "5": 0.0}
    assert r["actor_iou"] == {"1": 1.0, "2": 1.0} and r["latency_ms"] == 4.0
    wrong = MetricAccumulator(dt_s=dt)
    wrong.add(1.0 - truth, eta * 1.01, eta, valid, instance)
    r = wrong.result()
    assert r["miou"] == 0.0 and r["error_rate"]["1"] == 1.0 and r["actor_iou"]["2"] == 0.0
    assert r["mid"] == pytest.approx(np.log(1.01) * 1e4)


def test_breakdown_errors_by_margin_to_the_threshold():
    """One image whose pixels sit at known margins from one mIoU level's eta; that level's
    map is read 0.015 too high in log eta (the pixels just inside fall out), the others exact."""
    dt = 0.1
    acc = MetricAccumulator(dt_s=dt)
    k = 5
    eta_k = tau_to_eta(acc.miou_thresholds_s[k], dt)
    margins = np.array([-0.1, -0.012, -0.003, 0.003, 0.012, 0.1])  # log eta - log eta_k
    eta = np.tile(eta_k * np.exp(margins), (2, 1))
    valid = np.ones(eta.shape, bool)
    prob = np.stack([(eta <= tau_to_eta(t, dt)) for t in acc.thresholds_s]).astype(np.float32)
    prob[k] = eta * np.exp(0.015) <= eta_k
    acc.add(prob, None, eta, valid, np.zeros(eta.shape, np.int64))
    b = acc.result()["breakdown"]
    by = b["errors_by_margin_log_eta"]
    # the wrong pixels: margins -0.012 and -0.003 (two rows each), 4 errors in all
    assert by["<0.005"]["share_of_errors"] == pytest.approx(0.5)
    assert by["0.01-0.02"]["share_of_errors"] == pytest.approx(0.5)
    assert by["0.005-0.01"]["share_of_errors"] == 0.0
    # within < 0.005 sit the +-0.003 pixels of threshold k only: half of them wrong
    assert by["<0.005"]["error_rate"] == pytest.approx(0.5)
    assert sum(g["share_of_pixels"] for g in by.values()) == pytest.approx(1.0)
    f = b["miou_forgiving_margin_log_eta"]
    assert f["0.02"] == pytest.approx(1.0) and f["0.04"] == pytest.approx(1.0)
    # forgiving < 0.01 rights the -0.003 pixels only; threshold k keeps the -0.012 ones wrong:
    # inside I=4, U=6; outside I=6, U=8 -> (2/3 + 3/4) / 2, averaged with 9 perfect levels
    assert f["0.01"] == pytest.approx((9 + (2 / 3 + 3 / 4) / 2) / 10)
    assert acc.result()["miou"] < f["0.01"]


def test_breakdown_groups_pairs_by_inside_share():
    dt = 0.1
    acc = MetricAccumulator(dt_s=dt)
    n = len(acc.miou_thresholds_s)
    # image 1: nothing inside any geofence, one false inside pixel in every map
    eta = np.full((10, 10), 0.99)
    prob = np.zeros((len(acc.thresholds_s), 10, 10), np.float32)
    prob[:, 0, 0] = 1.0
    prob[:3, 0, 0] = 0.0  # the three shortest geofences right: nothing inside, nothing said
    valid, static = np.ones(eta.shape, bool), np.zeros(eta.shape, np.int64)
    acc.add(prob, eta * np.exp(0.01), eta, valid, static)
    # image 2: a 3-pixel actor at 0.15 s (3 % of the pixels), predicted exactly
    eta2 = np.full((10, 10), 0.99)
    eta2[0, :3] = tau_to_eta(0.15, dt)
    actor = np.zeros(eta.shape, np.int64)
    actor[0, :3] = 1
    truth = np.stack([(eta2 <= tau_to_eta(t, dt)) for t in acc.thresholds_s]).astype(np.float32)
    acc.add(truth, eta2, eta2, valid, actor)
    b = acc.result()["breakdown"]
    wrong = (0 + 99 / 100) / 2  # inside IoU 0, outside 99 / 100
    assert b["by_inside_share"]["0"] == {
        "pairs": n,
        "miou": pytest.approx((3 * 1.0 + (n - 3) * wrong) / n),
        "inside_iou": 0.0,
        "pairs_with_inside_union": n - 3,
        "false_inside_px_median": 1.0,
        "false_inside_px_p90": 1.0,
    }
    assert b["by_inside_share"]["0-5%"] == {
        "pairs": n,
        "miou": 1.0,
        "inside_iou": 1.0,
        "pairs_with_inside_union": n,
        "false_inside_px_median": 0.0,
        "false_inside_px_p90": 0.0,
    }
    assert b["by_inside_share"]["20-100%"]["pairs"] == 0 and math.isnan(b["by_inside_share"]["20-100%"]["miou"])
    by_t = list(b["miou_by_threshold_s"].values())
    assert by_t == pytest.approx([1.0] * 3 + [(wrong + 1.0) / 2] * (n - 3))
    assert list(b["miou_by_threshold_s"]) == [threshold_key(t) for t in acc.miou_thresholds_s]
    assert b["mid_actor"] == pytest.approx(0.0) and b["mid_static"] == pytest.approx(0.01 * 1e4 * 100 / 197)


def test_breakdown_by_ego_speed():
    dt = 0.1
    acc = MetricAccumulator(dt_s=dt)
    assert "by_ego_speed_mps" not in acc.result()["breakdown"]  # no speeds given
    k1 = len(acc.miou_thresholds_s) + list(acc.thresholds_s[len(acc.miou_thresholds_s) :]).index(1.0)
    valid = np.ones((4, 5), bool)
    instance = np.zeros((4, 5), np.int64)
    instance[0, 0] = 1  # an actor pixel: not static, left out of the static error
    # standing ego: static world at eta = 1 (tau = inf); the map at 1 s says 5 static pixels are inside
    eta = np.ones((4, 5))
    prob = np.zeros((len(acc.thresholds_s), 4, 5), np.float32)
    prob[k1, 3, :] = 1.0
    prob[k1, 0, 0] = 1.0  # the actor pixel, wrong too
    acc.add(prob, None, eta, valid, instance, ego_speed_mps=0.0)
    # moving ego: the bottom row at 0.5 s, the rest far; the map at 1 s misses 2 of the 5
    eta2 = np.full((4, 5), 0.999)
    eta2[3, :] = tau_to_eta(0.5, dt)
    truth = np.stack([(eta2 <= tau_to_eta(t, dt)) for t in acc.thresholds_s]).astype(np.float32)
    truth[k1, 3, :2] = 0.0
    acc.add(truth, None, eta2, valid, instance, ego_speed_mps=20.0)
    b = acc.result()["breakdown"]["by_ego_speed_mps"]
    assert list(b) == ["<0.5", "0.5-5", "5-15", ">=15"]
    assert b["<0.5"]["images"] == 1 and b["<0.5"]["miou"] == pytest.approx(1.0)  # the metric maps were right
    assert b["<0.5"]["static_false_inside_1s"] == pytest.approx(5 / 19) and b["<0.5"]["static_missed_1s"] == 0.0
    assert b[">=15"]["static_missed_1s"] == pytest.approx(2 / 19) and b[">=15"]["static_false_inside_1s"] == 0.0
    assert b["0.5-5"]["images"] == 0 and math.isnan(b["0.5-5"]["miou"])


def test_inside_share_group_edges():
    assert inside_share_group(0, 1000) == "0" and inside_share_group(0, 0) == "0"
    assert inside_share_group(49, 1000) == "0-5%" and inside_share_group(50, 1000) == "5-20%"
    assert inside_share_group(199, 1000) == "5-20%" and inside_share_group(200, 1000) == "20-100%"
    assert inside_share_group(1000, 1000) == "20-100%"
    assert threshold_key(1.08888) == "1.0889" and threshold_key(2.0) == "2"


def test_ttc_conventions():
    assert eta_to_tau(0.5, 0.1) == pytest.approx(0.1)
    assert eta_to_tau(1.0, 0.1) == np.inf
    assert eta_to_tau(1.25, 0.1) == pytest.approx(-0.5)
    assert tau_to_eta(eta_to_tau(0.93, 0.1), 0.1) == pytest.approx(0.93)


def test_eval_of_the_oracle_is_perfect_and_writes_json(tmp_path):
    import argparse
    import json

    from sim.cli import eval_cmd

    out = tmp_path / "o.json"
    a = argparse.Namespace(
        data="synthetic",
        method="oracle",
        weights=None,
        out=str(out),
        split="val",
        limit=2,
        device="cpu",
        tta="none",
        scenarios=None,
        kitti_raw=None,
        strides=None,
        frame_stride=None,
        backend="torch",
        onnx=None,
    )
    assert eval_cmd.run(a) == 0
    r = json.loads(out.read_text())
    assert r["miou"] == pytest.approx(1.0) and r["mid"] == pytest.approx(0.0) and r["pairs"] == 2
    assert set(r["error_rate"]) == {"1", "2", "5"} and set(r["actor_iou"]) == {"1", "2"}
    assert r["latency_ms"] > 0
    from bittc_core.errors import CliError

    with pytest.raises(CliError, match="--limit 0"):
        eval_cmd.run(argparse.Namespace(**{**vars(a), "limit": 0}))
    with pytest.raises(CliError, match="--method 'magic'"):
        eval_cmd.run(argparse.Namespace(**{**vars(a), "method": "magic"}))
    with pytest.raises(CliError, match="--tta 'mirror'"):
        eval_cmd.run(argparse.Namespace(**{**vars(a), "tta": "mirror"}))
    with pytest.raises(CliError, match="--tta 'flip' applies to --method bittc only"):
        eval_cmd.run(argparse.Namespace(**{**vars(a), "tta": "flip"}))
    assert not list(tmp_path.glob(".*.tmp"))
    # oracle-auc: exact geofences, the continuous output quantized by the AUC volume
    assert eval_cmd.run(argparse.Namespace(**{**vars(a), "method": "oracle-auc"})) == 0
    r = json.loads(out.read_text())
    assert r["miou"] == pytest.approx(1.0) and r["method"] == "oracle-auc" and 0 < r["mid"] < 300


def test_eval_tta_modes_match_the_estimator():
    from bittc_core.estimator import METHODS, TTA_MODES
    from sim.cli import eval_cmd

    assert eval_cmd.TTA_MODES == TTA_MODES and eval_cmd.METHODS == METHODS
