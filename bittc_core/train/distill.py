"""Self-distillation targets: a frozen teacher's flip-averaged geofence logits.

Flip averaging (``bittc_core.model.flip``) makes a better estimator than one pass of
the same weights at about twice the cost; training a student towards the averaged maps of a
frozen teacher (soft BCE targets beside the ground truth) moves part of that gain into
the single pass, at no inference cost.
"""

from __future__ import annotations

import torch

from bittc_core.model import BinaryTTCNet
from bittc_core.model.flip import flip_views, merge_flip_views


@torch.no_grad()
def flip_averaged_logits(
    teacher: BinaryTTCNet, image_prev: torch.Tensor, image_latest: torch.Tensor, eta: torch.Tensor
) -> torch.Tensor:
    """Images (B, 3, H, W), eta thresholds (B, K) -> the teacher's logits of
    p(eta <= eta_i) averaged over the plain and the mirrored pair, (B, K, H, W) in the
    latest frame's grid. The teacher must be in eval mode (batch-norm statistics fixed)."""
    if teacher.training:
        raise ValueError("flip_averaged_logits: the teacher must be in eval mode")
    return merge_flip_views(teacher(flip_views(image_prev), flip_views(image_latest), eta.repeat(2, 1)))
