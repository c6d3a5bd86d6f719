"""Losses: masked BCE and a Lovasz IoU surrogate on binary maps, SmoothL1 on continuous log eta."""

from __future__ import annotations

import torch
import torch.nn.functional as F


def masked_bce(
    logits: torch.Tensor, labels: torch.Tensor, mask: torch.Tensor, weight: torch.Tensor | None = None
) -> torch.Tensor:
    """Mean BCE over pixels where ``mask`` (broadcast to the logits' shape) is true;
    with ``weight`` (broadcast likewise) the weighted mean."""
    mask = mask.expand_as(logits)
    if not mask.any():
        return logits.sum() * 0.0
    if weight is None:
        return F.binary_cross_entropy_with_logits(logits[mask], labels[mask])
    w = weight.expand_as(logits)[mask]
    per_px = F.binary_cross_entropy_with_logits(logits[mask], labels[mask], reduction="none")
    return (per_px * w).sum() / w.sum()


def masked_smooth_l1(pred: torch.Tensor, target: torch.Tensor, mask: torch.Tensor, unit: float) -> torch.Tensor:
    """SmoothL1 (beta = 1) of (pred - target) / unit over ``mask``; ``unit`` = one eta bin."""
    if not mask.any():
        return pred.sum() * 0.0
    return F.smooth_l1_loss(pred[mask] / unit, target[mask] / unit)


def _jaccard_gains(gt_sorted: torch.Tensor) -> torch.Tensor:
    """Per-position gains of the Jaccard loss 1 - |y & pred| / |y | pred| as the pixels,
    sorted by error (largest first), are counted wrong one after the other (the
    Lovasz extension's weights, Berman et al. 2018). gt_sorted (N, P) float 0/1."""
    positives = gt_sorted.sum(dim=1, keepdim=True)
    intersection = positives - gt_sorted.cumsum(dim=1)
    union = positives + (1.0 - gt_sorted).cumsum(dim=1)
    jaccard = 1.0 - intersection / union  # union >= 1 from the first position on
    return torch.cat((jaccard[:, :1], jaccard[:, 1:] - jaccard[:, :-1]), dim=1)


def lovasz_two_class(logits: torch.Tensor, labels: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
    """Lovasz-softmax surrogate of 1 - (IoU of the inside class + IoU of the outside class) / 2
    per map, averaged over maps: the per-image two-class IoU that the Table 1 mIoU averages.

    logits, labels (B, K, H, W); ``mask`` broadcast to them selects the pixels scored. A map
    whose class is absent from the labels scores that class by its most confident wrong
    pixel (a stray inside pixel halves the metric of an empty geofence). At hard 0/1
    predictions the value equals 1 - mean IoU of the classes with a non-empty union, up
    to maps where a class is absent from both labels and prediction (the metric skips
    that class, here it scores IoU 1)."""
    mask = mask.expand_as(logits).flatten(2).flatten(0, 1)
    prob = torch.sigmoid(logits).flatten(2).flatten(0, 1)
    gt = labels.flatten(2).flatten(0, 1)
    # masked pixels: error -1 sorts them last (after every real error >= 0), weight unused
    errors = torch.where(mask, (gt - prob).abs(), torch.full_like(prob, -1.0))
    errors_sorted, order = errors.sort(dim=1, descending=True)
    gt_sorted = torch.where(mask, gt, 0.0).gather(1, order)
    out_sorted = torch.where(mask, 1.0 - gt, 0.0).gather(1, order)
    gains = _jaccard_gains(gt_sorted) + _jaccard_gains(out_sorted)
    return 0.5 * (errors_sorted.clamp(min=0.0) * gains).sum(dim=1).mean()
