"""The correlation volume: group means in either memory layout, the unpadded shortcut and
SegNet's convs of it placed on the padded grid, the sign it carries."""

import math

import pytest
import torch

from bittc_core.model.config import ModelConfig
from bittc_core.model.correlation import CORR_OFFSETS, group_correlation, scale_correlation, shifted_correlation
from bittc_core.model.segnet import SegNet2D, SegNetInputs
from bittc_core.model.warp import PaddedGrid, column_warp, scale_warp


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


class _PaddedCorrSegNet(SegNet2D):
    """SegNet with its correlation convs run on the zero-padded volume (the reference)."""

    def _corr_first(self, corr, grid, size_hw):
        return self.corr_first(grid.pad(corr))

    def _corr_last(self, corr, box, size_hw):
        grid = PaddedGrid(box.h, box.w, self._hp, self._wp, box.top + box.inner_top, box.left + box.inner_left)
        return self.corr_last(box.cut(grid.pad(corr)))


@pytest.mark.parametrize("h, w", [(10, 14), (11, 13), (16, 32), (7, 9), (9, 20)])
def test_segnet_places_its_correlation_convs_as_on_the_padded_volume(h, w):
    """SegNet's output with the convs of the unpadded volume placed on the padded grid equals
    its output with the convs run on the zero-padded volume: at odd and even offsets of the
    map, and with no padding at all."""
    g = torch.Generator().manual_seed(4)
    kw = dict(feat_channels=4, enc_channels=(6, 8), dec_channels=(8, 6), full_res_skip=True, norm="none")
    net = SegNet2D(**kw, corr_channels=6).eval()
    ref_net = _PaddedCorrSegNet(**kw, corr_channels=6).eval()
    for p in net.parameters():
        p.data.normal_(0.0, 0.3, generator=g)
    ref_net.load_state_dict(net.state_dict())
    for pad_factor in (1.5, 1.0):
        grid = PaddedGrid.for_features(h, w, pad_factor, 4)
        ref_net._hp, ref_net._wp = grid.hp, grid.wp
        feat_ref, src = torch.randn(1, 4, h, w, generator=g), torch.randn(1, 4, h, w, generator=g)
        eta = torch.tensor([[0.8, 0.95]])
        warped = scale_warp(src, eta, grid)
        corr = torch.randn(2, 6, h, w, generator=g)
        with torch.no_grad():
            out = net(net.prepare(grid.pad(feat_ref), grid), SegNetInputs(warped, corr), grid)
            expected = ref_net(ref_net.prepare(grid.pad(feat_ref), grid), SegNetInputs(warped, corr), grid)
        assert out.shape == (2, 3, h, w)
        torch.testing.assert_close(out, expected)
        assert not torch.allclose(out, net(net.prepare(grid.pad(feat_ref), grid), SegNetInputs(warped, None), grid))


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


def _shifted(ref, warped, groups, max_shift, d):
    """group_correlation of ref(x) with warped(x + d), zero beyond the map's sides."""
    w = warped.shape[-1]
    moved = torch.zeros_like(warped)
    lo, hi = max(0, -d), min(w, w - d)
    moved[..., lo:hi] = warped[..., lo + d : hi + d]
    return group_correlation(ref, moved, groups)


@pytest.mark.parametrize("layout", [torch.contiguous_format, torch.channels_last])
def test_shifted_correlation_is_the_largest_over_the_shifts(layout):
    """Each pixel and group: the maximum over d = -s ... s of the correlation with the map
    moved by d columns; the same with and without autograd, in either layout."""
    g = torch.Generator().manual_seed(5)
    ref, warped = torch.randn(2, 6, 4, 9, generator=g), torch.randn(6, 6, 4, 9, generator=g)  # B=2, K=3
    expected = torch.stack([_shifted(ref, warped, 3, 2, d) for d in range(-2, 3)]).amax(dim=0)
    ref_l, warped_l = ref.contiguous(memory_format=layout), warped.contiguous(memory_format=layout)
    with torch.no_grad():
        out = shifted_correlation(ref_l, warped_l, 3, 2)
    assert out.shape == (6, 3, 4, 9)
    torch.testing.assert_close(out, expected)
    assert out.is_contiguous(memory_format=layout)
    # with autograd: the same values, and the gradient of the reference computation
    weights = torch.randn(expected.shape, generator=g)
    warped_g = warped.clone().requires_grad_(True)
    (torch.stack([_shifted(ref, warped_g, 3, 2, d) for d in range(-2, 3)]).amax(dim=0) * weights).sum().backward()
    warped_l.requires_grad_(True)
    out = shifted_correlation(ref_l, warped_l, 3, 2)
    torch.testing.assert_close(out, expected)
    (out * weights).sum().backward()
    torch.testing.assert_close(warped_l.grad, warped_g.grad)


def test_shifted_correlation_finds_a_target_moved_sideways():
    """ref is the source moved 2 columns: the plain correlation of the aligned warp is low,
    the shifted one finds the move (up to s = 2) and misses it at s = 1."""
    g = torch.Generator().manual_seed(6)
    src = torch.randn(1, 8, 6, 20, generator=g)
    ref = torch.zeros_like(src)
    ref[..., 2:] = src[..., :-2]  # ref(x) = src(x - 2)
    inner = (..., slice(4, 16))
    plain = group_correlation(ref, src, 4)[inner].mean()
    found = shifted_correlation(ref, src, 4, 2)[inner].mean()
    short = shifted_correlation(ref, src, 4, 1)[inner].mean()
    assert found > 0.8 and found > short + 0.3 and found > plain + 0.3


def test_scale_correlation_appends_the_shifted_channels():
    g = torch.Generator().manual_seed(7)
    grid = PaddedGrid.for_features(8, 12, 1.5, 4)
    ref, src = torch.randn(1, 8, 8, 12, generator=g), torch.randn(1, 8, 8, 12, generator=g)
    eta = torch.tensor([[0.8, 1.0]])
    warped = scale_warp(src, eta, grid)
    plain = scale_correlation(ref, src, eta, warped, grid, 4, 0.05)
    both = scale_correlation(ref, src, eta, warped, grid, 4, 0.05, max_shift=1)
    assert both.shape == (2, 24, 8, 12)
    torch.testing.assert_close(both[:, :12], plain)
    middle = grid.crop(warped)
    torch.testing.assert_close(both[:, 16:20], shifted_correlation(ref, middle, 4, 1))


def test_scale_correlation_appends_the_column_channels_last():
    """With ``column`` the volume ends in the group correlations of the three column warps,
    after the centre warps' (and the shifted ones'), each at its own eta."""
    g = torch.Generator().manual_seed(8)
    grid = PaddedGrid.for_features(8, 12, 1.5, 4)
    ref, src = torch.randn(1, 8, 8, 12, generator=g), torch.randn(1, 8, 8, 12, generator=g)
    eta, step = torch.tensor([[0.8, 1.0]]), 0.05
    warped = scale_warp(src, eta, grid)
    shifted = scale_correlation(ref, src, eta, warped, grid, 4, step, max_shift=1)
    every = scale_correlation(ref, src, eta, warped, grid, 4, step, max_shift=1, column=True)
    assert every.shape == (2, 36, 8, 12)
    torch.testing.assert_close(every[:, :24], shifted)
    for j, offset in enumerate(CORR_OFFSETS):
        columns = column_warp(src, eta * math.exp(offset * step), grid, unpadded=True)
        torch.testing.assert_close(every[:, 24 + 4 * j : 28 + 4 * j], group_correlation(ref, columns, 4))
    # about the centre, the column warp at eta 1 is the identity, as the centre warp is
    torch.testing.assert_close(every[1:, 28:32], every[1:, 4:8])


def test_column_warp_keeps_columns_and_scales_rows_as_the_centre_warp():
    """Where the source varies only down the columns, the two warps agree; where it varies
    only along the rows, the column warp leaves it be and the centre warp scales it."""
    grid = PaddedGrid.for_features(9, 15, 1.5, 4)
    eta = torch.tensor([[0.7, 0.9]])
    rows = torch.linspace(0.0, 1.0, 9)[:, None].expand(9, 15)[None, None]
    cols = torch.linspace(0.0, 1.0, 15)[None, :].expand(9, 15)[None, None]
    torch.testing.assert_close(column_warp(rows, eta, grid, unpadded=True), scale_warp(rows, eta, grid, unpadded=True))
    kept = column_warp(cols, eta, grid, unpadded=True)
    torch.testing.assert_close(kept, cols.expand(2, 1, 9, 15))
    assert not torch.allclose(scale_warp(cols, eta, grid, unpadded=True), kept)


def test_column_correlations_need_the_volume():
    with pytest.raises(ValueError, match="corr_column=True: needs the correlation volume"):
        ModelConfig(corr_column=True)


def test_shifted_correlation_needs_whole_groups():
    with pytest.raises(ValueError, match="6 channels do not split into 4 groups"):
        shifted_correlation(torch.zeros(1, 6, 2, 3), torch.zeros(2, 6, 2, 3), 4, 1)


def test_shifted_correlation_needs_the_volume():
    with pytest.raises(ValueError, match="corr_shift_px=2: needs the correlation volume"):
        ModelConfig(corr_shift_px=2)
    with pytest.raises(ValueError, match="corr_shift_px=-1: must be >= 0"):
        ModelConfig(corr_groups=8, corr_shift_px=-1)


def test_segnet_reads_each_part_of_the_volume_through_its_own_convs():
    """The volume's channels go centre, shifted, column: each part's convs read its slice
    only, so a part whose convs are zero may hold anything, and a part whose convs are
    live changes the output."""
    g = torch.Generator().manual_seed(5)
    h, w = 6, 9
    kw = dict(feat_channels=4, enc_channels=(6, 8), dec_channels=(8, 6), full_res_skip=True, norm="none")
    net = SegNet2D(**kw, corr_channels=6, shift_channels=6, column_channels=6).eval()
    assert net.volume_parts == (("corr", 6), ("shift", 6), ("column", 6))
    for p in net.parameters():
        p.data.normal_(0.0, 0.3, generator=g)
    grid = PaddedGrid.for_features(h, w, 1.5, 4)
    terms = net.prepare(grid.pad(torch.randn(1, 4, h, w, generator=g)), grid)
    warped = scale_warp(torch.randn(1, 4, h, w, generator=g), torch.tensor([[0.8, 0.95]]), grid)
    corr = torch.randn(2, 18, h, w, generator=g)
    for i, part in enumerate(("corr", "shift", "column")):
        other = corr.clone()
        other[:, 6 * i : 6 * i + 6] = torch.randn(2, 6, h, w, generator=g)
        with torch.no_grad():
            assert not torch.allclose(
                net(terms, SegNetInputs(warped, corr), grid), net(terms, SegNetInputs(warped, other), grid)
            )
            live = [getattr(net, f"{part}_{end}").weight.clone() for end in ("first", "last")]
            getattr(net, f"{part}_first").weight.zero_()
            getattr(net, f"{part}_last").weight.zero_()
            torch.testing.assert_close(
                net(terms, SegNetInputs(warped, corr), grid), net(terms, SegNetInputs(warped, other), grid)
            )
            getattr(net, f"{part}_first").weight.copy_(live[0])
            getattr(net, f"{part}_last").weight.copy_(live[1])
