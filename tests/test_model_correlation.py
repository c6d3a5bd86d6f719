"""The correlation volume: group means, the unpadded shortcut, the sign it carries."""

import math

import pytest
import torch

from bittc_core.model.correlation import CORR_OFFSETS, group_correlation, scale_correlation
from bittc_core.model.warp import PaddedGrid, scale_warp


def test_group_correlation_is_the_mean_product_per_group():
    g = torch.Generator().manual_seed(0)
    ref, warped = torch.randn(2, 6, 4, 5, generator=g), torch.randn(6, 6, 4, 5, generator=g)  # B=2, K=3
    out = group_correlation(ref, warped, groups=3)
    assert out.shape == (6, 3, 4, 5)
    for n in range(6):
        for grp in range(3):
            ch = slice(2 * grp, 2 * grp + 2)
            expected = (ref[n // 3, ch] * warped[n, ch]).mean(dim=0)
            torch.testing.assert_close(out[n, grp], expected)
    with pytest.raises(ValueError, match="6 channels do not split into 4 groups"):
        group_correlation(ref, warped, groups=4)


def test_unpadded_computation_equals_the_padded_one():
    g = torch.Generator().manual_seed(1)
    grid = PaddedGrid.for_features(10, 14, 1.5, 4)
    ref, src = torch.randn(2, 8, 10, 14, generator=g), torch.randn(2, 8, 10, 14, generator=g)
    eta = torch.tensor([[0.7, 1.0, 1.2], [0.9, 0.95, 1.1]])
    step = 0.05
    out = scale_correlation(ref, src, eta, scale_warp(src, eta, grid), grid, 4, step)
    expected = torch.cat(
        [group_correlation(grid.pad(ref), scale_warp(src, eta * math.exp(o * step), grid), 4) for o in CORR_OFFSETS],
        dim=1,
    )
    assert out.shape == (6, 12, grid.hp, grid.wp)
    torch.testing.assert_close(out, expected)


def test_outer_warps_tell_the_side_of_the_threshold():
    """ref is src scaled by the true eta; for a threshold above the true eta the warp
    below it (offset -1) matches better than the one above, and the other way round."""
    g = torch.Generator().manual_seed(2)
    h, w = 24, 48
    # smooth random features: upsampled noise
    src = torch.nn.functional.interpolate(
        torch.randn(1, 8, 6, 12, generator=g), size=(h, w), mode="bicubic", align_corners=True
    )
    grid = PaddedGrid.for_features(h, w, 1.5, 4)
    eta_true, step = 0.9, 0.05
    ref = grid.crop(scale_warp(src, torch.tensor([[eta_true]]), grid))
    eta = torch.tensor([[eta_true * math.exp(step), eta_true * math.exp(-step)]])
    corr = grid.crop(scale_correlation(ref, src, eta, scale_warp(src, eta, grid), grid, 2, step))
    groups = 2
    low, high = corr[:, :groups].mean(dim=(1, 2, 3)), corr[:, 2 * groups :].mean(dim=(1, 2, 3))
    assert low[0] > high[0]  # threshold above the truth: the lower warp is the true one
    assert high[1] > low[1]  # threshold below the truth: the upper warp is
