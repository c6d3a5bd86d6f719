"""Group-wise correlation of the reference and the warped source features (not in the paper).

The paper feeds SegNet the concatenation [f_ref, P_phi(f_src)] only. A conv over a
concatenation sums its parts and cannot form their product, so a small network has to
spend layers on telling how well the warp aligned the two. Here, per hypothesis eta_i,
the source is also warped at eta_i * exp(-s) and eta_i * exp(+s) (s = ``log_step``), and
for each of the three warps the features are compared group by group (GwcNet, Guo et
al., CVPR 2019: the channels split into G groups, the mean over each group of the
product f_ref * f_src):

    corr[j, g](x) = mean_{c in group g} f_ref[c](x) * warp(f_src, eta_i * exp(o_j s))[c](x)

with o = (-1, 0, +1). Where the pixel's eta is eta_i, the middle one peaks; which of the
outer ones is larger says on which side of the threshold eta lies. Shapes: reference
(B, C, h, w), warps (B*K, C, ., .) batch-major -> (B*K, 3G, h, w) on the unpadded map.
"""

from __future__ import annotations

import math

import torch

from bittc_core.model.warp import PaddedGrid, scale_warp

#: offsets of the three correlation warps, in units of ``log_step`` of log eta
CORR_OFFSETS = (-1.0, 0.0, 1.0)


def group_correlation(ref: torch.Tensor, warped: torch.Tensor, groups: int) -> torch.Tensor:
    """ref (B, C, h, w), warped (B*K, C, h, w) -> (B*K, G, h, w), mean product per group.
    Channels-last inputs (channels innermost, a crop of such a map included) give a
    channels-last output, with no layout change."""
    b, c, h, w = ref.shape
    if c % groups:
        raise ValueError(f"group_correlation: {c} channels do not split into {groups} groups")
    k = warped.shape[0] // b
    n = c // groups
    if not torch.compiler.is_compiling() and c > 1 and warped.stride(1) == 1 and ref.stride(1) == 1:
        prod = warped.permute(0, 2, 3, 1).reshape(b, k, h, w, groups, n) * ref.permute(0, 2, 3, 1).reshape(
            b, 1, h, w, groups, n
        )
        return prod.mean(dim=-1).view(b * k, h, w, groups).permute(0, 3, 1, 2)
    prod = warped.view(b, k, groups, n, h, w) * ref.view(b, 1, groups, n, h, w)
    return prod.mean(dim=3).view(b * k, groups, h, w)


def scale_correlation(
    ref: torch.Tensor,
    src: torch.Tensor,
    eta: torch.Tensor,
    warped: torch.Tensor,
    grid: PaddedGrid,
    groups: int,
    log_step: float,
) -> torch.Tensor:
    """Correlation volume of the three warps about each eta (B, K) -> (B*K, 3G, h, w), on
    the unpadded map.

    ``ref`` (B, C, h, w) are the unpadded reference features, ``warped`` is
    ``scale_warp(src, eta, grid)``, already computed for SegNet's input. The reference is
    zero in the padding, so is the correlation there: it is computed on the unpadded map
    only (the outer warps too) and never padded; SegNet places what its convs make of it
    (``SegNet2D.forward``)."""
    parts = []
    for offset in CORR_OFFSETS:
        if offset == 0.0:
            w = grid.crop(warped)
        else:
            w = scale_warp(src, eta * math.exp(offset * log_step), grid, unpadded=True)
        parts.append(group_correlation(ref, w, groups))
    return torch.cat(parts, dim=1)
