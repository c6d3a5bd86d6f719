"""Training's losses and targets: the weighted BCE, the Lovasz term against the two-class
IoU, the binary labels, the band just outside each fence, and where a pair's thresholds
are drawn (at pixels' eta, at the in-path vehicle's)."""

import math

import pytest
import torch

from bittc_core.metrics import class_counts, two_class_iou
from bittc_core.train import TrainConfig
from bittc_core.train.losses import lovasz_two_class, masked_bce
from bittc_core.train.losses_stage import stage_losses
from bittc_core.train.targets import (
    INPATH_THRESHOLD_JITTER,
    PIXEL_THRESHOLD_JITTER,
    eta_labels,
    near_outside,
    sample_eta_at_pixels,
    shift_labels,
)
from bittc_core.ttc import tau_to_eta
from tests.train_helpers import make_trainer


def test_weighted_bce():
    logits = torch.tensor([[[2.0, -1.0, 0.5]]])
    labels = torch.tensor([[[1.0, 1.0, 0.0]]])
    mask = torch.tensor([[[True, True, False]]])
    plain = masked_bce(logits, labels, mask)
    assert torch.allclose(masked_bce(logits, labels, mask, torch.full_like(logits, 3.0)), plain)
    per = torch.nn.functional.binary_cross_entropy_with_logits(logits, labels, reduction="none")[0, 0]
    weighted = masked_bce(logits, labels, mask, torch.tensor([[[1.0, 4.0, 9.0]]]))
    assert torch.allclose(weighted, (per[0] + 4 * per[1]) / 5)  # the masked pixel's weight is unused


def test_lovasz_equals_the_two_class_iou_loss_at_hard_predictions():
    gen = torch.Generator().manual_seed(0)
    labels = (torch.rand(3, 2, 9, 11, generator=gen) < 0.3).float()
    labels[1, 0] = 0.0  # empty geofence: one stray pixel below halves the metric
    wrong = torch.rand(3, 2, 9, 11, generator=gen) < 0.2
    pred = torch.where(wrong, 1.0 - labels, labels)
    pred[1, 0] = 0.0
    pred[1, 0, 4, 5] = 1.0
    mask = torch.rand(3, 1, 9, 11, generator=gen) < 0.9
    mask[1] = True
    logits = 40.0 * (2.0 * pred - 1.0)  # saturated: sigmoid 0 or 1
    expected = [
        1.0 - two_class_iou(class_counts(pred[i, k].bool().numpy(), labels[i, k].bool().numpy(), mask[i, 0].numpy()))
        for i in range(3)
        for k in range(2)
    ]
    assert expected[2] == pytest.approx(1.0 - 0.5 * (1.0 - 1 / 99))
    assert lovasz_two_class(logits, labels, mask).item() == pytest.approx(sum(expected) / 6, abs=1e-5)
    # perfect predictions: zero
    assert lovasz_two_class(40.0 * (2.0 * labels - 1.0), labels, mask).item() == pytest.approx(0.0, abs=1e-6)


def test_labels():
    eta = torch.tensor([[[0.5, 0.9, 1.0, 1.2, -1.0]]])
    lab = eta_labels(eta, torch.tensor([[0.9, 1.1]]))
    assert lab[0, 0, 0].tolist() == [1, 1, 0, 0, 0] and lab[0, 1, 0].tolist() == [1, 1, 1, 0, 0]
    flow = torch.tensor([[[[4.0, -2.0]], [[0.0, 7.0]]]])  # (1, 2, 1, 2)
    sl = shift_labels(flow, torch.tensor([[[3.0, 3.0]]]))
    assert sl[0, 0, 0, 0].tolist() == [1, 0] and sl[0, 0, 1, 0].tolist() == [0, 1]


def test_near_outside_marks_the_ttc_between_each_threshold_and_twice_it():
    tau = torch.tensor([0.5, 1.0, 1.5, 1.9, 2.05, 2.5, 30.0, math.inf, -2.0])
    eta = tau_to_eta(tau, 0.1).view(1, 1, -1)
    thr = tau_to_eta(torch.tensor([[1.0]]), 0.1)
    assert near_outside(eta, thr)[0, 0, 0].tolist() == [False, False, True, True, False, False, False, False, False]
    assert not near_outside(eta, torch.tensor([[1.05]])).any()  # a receding fence has no band


def test_pixel_thresholds_sit_at_pixel_eta_in_range():
    gen = torch.Generator().manual_seed(0)
    dt, lo = 0.1, tau_to_eta(0.2, 0.1)
    eta = torch.full((3, 4, 5), 0.9)
    eta[0, 0, 0] = 0.7  # pair 0: two values in range
    eta[1] = 5.0  # pair 1: nothing in range -> uniform
    mask = torch.ones(3, 4, 5, dtype=torch.bool)
    mask[2] = False  # pair 2: nothing valid -> uniform
    thr = sample_eta_at_pixels(eta, mask, 200, 0.2, 1.1, dt, gen)
    assert thr.shape == (3, 200) and bool(((thr >= lo) & (thr <= 1.1)).all())
    near = lambda t, v: (t - v).abs() <= PIXEL_THRESHOLD_JITTER + 1e-6  # noqa: E731
    assert bool((near(thr[0], 0.9) | near(thr[0], 0.7)).all()) and near(thr[0], 0.7).any()
    for uniform in thr[1], thr[2]:  # spread over the range, not at one value
        assert uniform.min() < lo + 0.1 and uniform.max() > 1.0


def test_inpath_thresholds_sit_at_the_inpath_vehicle_eta(tmp_path):
    """The in-path share of a pair's thresholds lies within INPATH_THRESHOLD_JITTER of its
    in-path pixels' eta, after the pixel share; a pair without in-path pixels draws uniform."""
    tr = make_trainer(tmp_path, pixel_threshold_share=0.25, inpath_threshold_share=0.5)
    batch = next(iter(tr.loader))
    b, (h, w) = batch["eta"].shape[0], batch["eta"].shape[-2:]
    batch["eta"] = torch.full((b, h, w), 1.05)
    batch["eta"][:, :4, :4] = 0.93  # the in-path vehicle of each pair but the last
    batch["inpath"] = torch.zeros(b, h, w, dtype=torch.bool)
    batch["inpath"][:-1, :4, :4] = True
    seen = []
    real = tr.net.classify_eta
    tr.net.classify_eta = lambda ctx, feats, thr: seen.append(thr) or real(ctx, feats, thr)
    stage_losses(tr.net, tr.cfg, batch, torch.Generator().manual_seed(0), torch.device("cpu"))
    (thr,) = seen
    k = tr.cfg.thresholds_per_pair
    at_pixels, at_inpath = round(k * 0.25), round(k * 0.5)
    inpath = thr[:-1, at_pixels : at_pixels + at_inpath]
    assert inpath.numel() and bool(((inpath - 0.93).abs() <= INPATH_THRESHOLD_JITTER + 1e-6).all())
    assert not bool(((thr[-1, at_pixels : at_pixels + at_inpath] - 0.93).abs() <= INPATH_THRESHOLD_JITTER).all())
    with pytest.raises(ValueError, match="inpath_threshold_share=0.8"):
        TrainConfig(pixel_threshold_share=0.5, inpath_threshold_share=0.8)
