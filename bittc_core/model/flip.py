"""Mirror views: the flip self-ensemble shared by the estimator and distillation.

A pair mirrored left to right is a valid scene with the same motion in depth, so the
network's eta and TTC outputs on the mirrored pair, mirrored back, estimate the same
maps. Not so the binary flow maps p(u > u_i): a mirror flips the sign of u. Views
ride along the batch dimension: for a batch of B, rows [0, B) are the plain view and
rows [B, 2B) the mirrored one. Outputs have image x on their last axis.
"""

from __future__ import annotations

import torch


def flip_views(x: torch.Tensor) -> torch.Tensor:
    """(B, ..., W) -> (2B, ..., W): the plain rows, then the rows mirrored in x."""
    return torch.cat((x, x.flip(-1)))


def merge_flip_views(out: torch.Tensor) -> torch.Tensor:
    """(2B, ..., W) outputs of ``flip_views`` inputs -> (B, ..., W) in the plain grid: the
    mean of the plain rows and the mirrored rows mirrored back. For maps a mirror leaves
    unchanged (eta / TTC geofence logits, log eta); average logits or log eta, not
    probabilities or eta."""
    b = out.shape[0] // 2
    if out.shape[0] != 2 * b:
        raise ValueError(f"merge_flip_views: expected an even batch of views, got {out.shape[0]}")
    return 0.5 * (out[:b] + out[b:].flip(-1))
