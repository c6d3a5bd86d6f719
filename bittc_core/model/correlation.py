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

The scale warp aligns what moves along the camera's axis. A road user crossing the road
also moves sideways between the two frames, and at the warp of its own eta it still lies
d feature px to one side of where the reference has it. With ``max_shift`` s > 0 the
volume gains 3G channels (``shifted_correlation``): for each warp, the largest of its
group correlations with the warped source moved by d = -s ... s feature px along the
rows, so a target that moved sideways by up to s feature px compares with itself.

With ``column`` the volume gains 3G channels more, last: the group correlations of the
three warps made by ``column_warp`` (rows scaled about the centre row, each column in
place). A road user on a collision course keeps its bearing, so between the frames it
grows about its own column: there the column warp aligns it, where the scale warp about
the image centre misses it by (x - c)(1 - eta) feature px (x its column, c the centre's).
"""

from __future__ import annotations

import math

import torch
import torch.nn.functional as F

from bittc_core.model.warp import PaddedGrid, column_warp, scale_warp

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


def shifted_correlation(ref: torch.Tensor, warped: torch.Tensor, groups: int, max_shift: int) -> torch.Tensor:
    """ref (B, C, h, w), warped (B*K, C, h, w) -> (B*K, G, h, w): at each pixel x and group,
    the largest group correlation of ref(x) with warped(x + d) over d = -s ... s feature px
    along the row (s = ``max_shift``); beyond the map's sides the warped map is zero.

    Computed on planar (NCHW) copies, one channel of each group at a time: a group's
    channels are c = g n + j, so channel j of every group is the slice ``j::n``. Without
    autograd the sums and the maximum go into two buffers in place. The output has the
    warped map's layout (channels-last in, channels-last out)."""
    b, c, h, w = ref.shape
    if c % groups:
        raise ValueError(f"shifted_correlation: {c} channels do not split into {groups} groups")
    n = c // groups
    channels_last = c > 1 and warped.stride(1) == 1
    k = warped.shape[0] // b
    padded = F.pad(warped.contiguous(), (max_shift, max_shift)).view(b, k, c, h, w + 2 * max_shift)
    ref = ref.contiguous().view(b, 1, c, h, w)
    refs = [ref[:, :, j::n] for j in range(n)]
    srcs = [padded[:, :, j::n] for j in range(n)]
    in_place = not torch.is_grad_enabled()
    best = prod = None
    for d in range(2 * max_shift + 1):
        if in_place:
            prod = torch.mul(srcs[0][..., d : d + w], refs[0], out=prod)
            for j in range(1, n):
                prod.addcmul_(srcs[j][..., d : d + w], refs[j])
            best = prod.clone() if best is None else torch.maximum(best, prod, out=best)
        else:
            prod = sum(srcs[j][..., d : d + w] * refs[j] for j in range(n))
            best = prod if best is None else torch.maximum(best, prod)
    best = (best / n).view(b * k, groups, h, w)
    return best.contiguous(memory_format=torch.channels_last) if channels_last else best


def scale_correlation(
    ref: torch.Tensor,
    src: torch.Tensor,
    eta: torch.Tensor,
    warped: torch.Tensor,
    grid: PaddedGrid,
    groups: int,
    log_step: float,
    max_shift: int = 0,
    column: bool = False,
    column_warped: torch.Tensor | None = None,
) -> torch.Tensor:
    """Correlation volume of the three warps about each eta (B, K) -> (B*K, 3G, h, w), on
    the unpadded map; with ``max_shift`` > 0 the three warps' shifted correlations follow
    (3G channels), and with ``column`` the three column warps' correlations last (3G).

    ``ref`` (B, C, h, w) are the unpadded reference features, ``warped`` is
    ``scale_warp(src, eta, grid)``, already computed for SegNet's input. The reference is
    zero in the padding, so is the correlation there: it is computed on the unpadded map
    only (the outer warps too) and never padded; SegNet places what its convs make of it
    (``SegNet2D.forward``). ``column_warped``, where given, is ``column_warp(src, eta,
    grid)``, SegNet's second input: the centre column correlation reads it cropped
    instead of warping again (the same samples)."""
    warps = [
        grid.crop(warped) if offset == 0.0 else scale_warp(src, eta * math.exp(offset * log_step), grid, unpadded=True)
        for offset in CORR_OFFSETS
    ]
    parts = [group_correlation(ref, w, groups) for w in warps]
    if max_shift:
        parts += [shifted_correlation(ref, w, groups, max_shift) for w in warps]
    if column:
        parts += [
            group_correlation(
                ref,
                grid.crop(column_warped)
                if o == 0.0 and column_warped is not None
                else column_warp(src, eta * math.exp(o * log_step), grid, unpadded=True),
                groups,
            )
            for o in CORR_OFFSETS
        ]
    return torch.cat(parts, dim=1)
