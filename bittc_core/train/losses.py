"""Losses: masked BCE on binary maps, SmoothL1 on continuous log eta."""

from __future__ import annotations

import torch
import torch.nn.functional as F


def masked_bce(logits: torch.Tensor, labels: torch.Tensor, mask: torch.Tensor,
               weight: torch.Tensor | None = None) -> torch.Tensor:
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


def masked_smooth_l1(pred: torch.Tensor, target: torch.Tensor, mask: torch.Tensor,
                     unit: float) -> torch.Tensor:
    """SmoothL1 (beta = 1) of (pred - target) / unit over ``mask``; ``unit`` = one eta bin."""
    if not mask.any():
        return pred.sum() * 0.0
    return F.smooth_l1_loss(pred[mask] / unit, target[mask] / unit)
