"""The correlation volume: group means in either memory layout, the unpadded shortcut and
SegNet's convs of it placed on the padded grid, the sign it carries."""

import math

import pytest
import torch

from bittc_core.model.correlation import CORR_OFFSETS, group_correlation, scale_correlation
from bittc_core.model.segnet import SegNet2D, _MarginBox, _pad_to
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


def test_group_correlation_keeps_channels_last():
    """Channels-last inputs (a crop of a padded map among them) give the same numbers, in
    channels-last."""
    g = torch.Generator().manual_seed(3)
    cl = torch.channels_last
    ref, padded = torch.randn(2, 8, 6, 7, generator=g), torch.randn(4, 8, 9, 11, generator=g)
    warped = padded[..., 1:7, 2:9]
    expected = group_correlation(ref, warped.contiguous(), groups=4)
    out = group_correlation(ref.contiguous(memory_format=cl), padded.contiguous(memory_format=cl)[..., 1:7, 2:9], 4)
    assert out.is_contiguous(memory_format=cl)
    torch.testing.assert_close(out, expected)


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
    assert out.shape == (6, 12, 10, 14)
    torch.testing.assert_close(grid.pad(out), expected)


@pytest.mark.parametrize("h, w", [(10, 14), (11, 13), (16, 32), (7, 9)])
def test_segnet_places_its_correlation_convs_as_on_the_padded_volume(h, w):
    """The convs of the unpadded volume, placed on the padded grid, equal the convs of the
    zero-padded volume: at odd and even offsets of the map, and with no padding at all."""
    g = torch.Generator().manual_seed(4)
    net = SegNet2D(
        feat_channels=4, enc_channels=(6, 8), dec_channels=(8, 6), full_res_skip=True, norm="none", corr_channels=6
    ).eval()
    for layer in (net.corr_first, net.corr_last):
        layer.weight.data.normal_(generator=g)
    for pad_factor in (1.5, 1.0):
        grid = PaddedGrid.for_features(h, w, pad_factor, 4)
        corr = torch.randn(3, 6, h, w, generator=g)
        first_size = ((grid.hp + 1) // 2, (grid.wp + 1) // 2)
        torch.testing.assert_close(net._corr_first(corr, grid, first_size), net.corr_first(grid.pad(corr)))
        box = _MarginBox.around(grid, margin=2)
        placed = net.corr_last(box.cut(grid.pad(corr)))
        torch.testing.assert_close(
            _pad_to(net.corr_last(corr), box.inner_top, box.inner_left, placed.shape[-2:]), placed
        )


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
    corr = scale_correlation(ref, src, eta, scale_warp(src, eta, grid), grid, 2, step)
    groups = 2
    low, high = corr[:, :groups].mean(dim=(1, 2, 3)), corr[:, 2 * groups :].mean(dim=(1, 2, 3))
    assert low[0] > high[0]  # threshold above the truth: the lower warp is the true one
    assert high[1] > low[1]  # threshold below the truth: the upper warp is
