"""Scale and shift warps against closed forms (feature-pixel coordinates)."""

import pytest
import torch

from bittc_core.model.warp import PaddedGrid, scale_warp, shift_warp

H, W = 11, 17


def ramp(a: float = 0.7, b: float = -1.3, c: float = 5.0) -> torch.Tensor:
    """f(x, y) = a x + b y + c, (1, 2, H, W) (second channel = 2 f): bilinear is exact on it."""
    ys, xs = torch.meshgrid(torch.arange(H, dtype=torch.float64), torch.arange(W, dtype=torch.float64), indexing="ij")
    f = a * xs + b * ys + c
    return torch.stack((f, 2 * f))[None], (a, b, c)


def unpadded() -> PaddedGrid:
    return PaddedGrid(H, W, H, W, 0, 0)


def test_scale_warp_identity_at_eta_one():
    src = torch.randn(2, 3, H, W, dtype=torch.float64)
    out = scale_warp(src, torch.ones(2, 1, dtype=torch.float64), unpadded())
    torch.testing.assert_close(out, src)


@pytest.mark.parametrize("eta", [0.8, 0.95, 1.2])
def test_scale_warp_matches_closed_form(eta):
    src, (a, b, c) = ramp()
    out = scale_warp(src, torch.tensor([[eta]], dtype=torch.float64), unpadded())
    cx, cy = (W - 1) / 2, (H - 1) / 2
    ys, xs = torch.meshgrid(torch.arange(H, dtype=torch.float64), torch.arange(W, dtype=torch.float64), indexing="ij")
    sx, sy = cx + eta * (xs - cx), cy + eta * (ys - cy)  # warped_src(x) = src(c + eta (x - c))
    inside = (sx >= 0) & (sx <= W - 1) & (sy >= 0) & (sy <= H - 1)
    expected = a * sx + b * sy + c
    torch.testing.assert_close(out[0, 0][inside], expected[inside])
    torch.testing.assert_close(out[0, 1][inside], 2 * expected[inside])
    if eta > 1:
        assert not inside.all()


def test_shift_warp_matches_closed_form():
    src, (a, b, c) = ramp()
    u, v = 2.5, -1.25
    out = shift_warp(src, torch.tensor([[[u, v]]], dtype=torch.float64), unpadded())
    ys, xs = torch.meshgrid(torch.arange(H, dtype=torch.float64), torch.arange(W, dtype=torch.float64), indexing="ij")
    sx, sy = xs - u, ys - v  # warped_src(x) = src(x - s)
    inside = (sx >= 0) & (sx <= W - 1) & (sy >= 0) & (sy <= H - 1)
    torch.testing.assert_close(out[0, 0][inside], (a * sx + b * sy + c)[inside])


def test_integer_shift_moves_content_and_fills_zeros():
    src = torch.randn(1, 1, H, W, dtype=torch.float64)
    out = shift_warp(src, torch.tensor([[[3.0, 2.0]]], dtype=torch.float64), unpadded())
    torch.testing.assert_close(out[0, 0, 2:, 3:], src[0, 0, :-2, :-3])
    assert torch.all(out[0, 0, :2] == 0) and torch.all(out[0, 0, :, :3] == 0)


def test_padded_grid_keeps_content_that_leaves_the_frame():
    grid = PaddedGrid.for_features(H, W, pad_factor=1.5, multiple=4)
    assert grid.hp >= 1.5 * H and grid.wp >= 1.5 * W and grid.hp % 4 == 0 and grid.wp % 4 == 0
    src = torch.rand(1, 1, H, W, dtype=torch.float64) + 1.0  # strictly positive
    same = scale_warp(src, torch.ones(1, 1, dtype=torch.float64), grid)
    torch.testing.assert_close(grid.crop(same), src)
    assert same.sum() == pytest.approx(src.sum())  # the border ring is zero
    # a 4-px shift to the right moves the right edge into the padding instead of dropping it
    shifted = shift_warp(src, torch.tensor([[[4.0, 0.0]]], dtype=torch.float64), grid)
    assert shifted.sum() == pytest.approx(src.sum())


def test_hypotheses_are_batch_major():
    src = torch.randn(2, 1, H, W, dtype=torch.float64)
    eta = torch.tensor([[1.0, 0.9], [1.0, 0.8]], dtype=torch.float64)
    out = scale_warp(src, eta, unpadded())
    torch.testing.assert_close(out[0], src[0])
    torch.testing.assert_close(out[2], src[1])
    torch.testing.assert_close(out[3], scale_warp(src[1:], eta[1:, 1:], unpadded())[0])


def test_stem_feature_pixel_i_sees_input_pixels_3i_to_3i_plus_2():
    """The 1/3-resolution grid is centred where the warps and the upsampling assume."""
    import torch

    from bittc_core.model.config import get_config
    from bittc_core.model.extractor import FeatExtractNet

    cfg = get_config("tiny")
    net = FeatExtractNet(
        stem_channels=cfg.stem_channels,
        out_channels=cfg.feat_channels,
        res_blocks=1,
        pool_sizes=cfg.spp_pool_sizes,
        spp_channels=cfg.spp_channels,
        norm="none",
    ).eval()
    stem = net.stem[0][0]
    base = torch.zeros(1, 3, 12, 12)
    out0 = stem(base)
    for x in range(12):
        img = base.clone()
        img[0, :, 4, x] = 1.0
        changed = (stem(img) - out0).abs().sum(dim=(0, 1, 2)) > 0
        assert changed.nonzero().flatten().tolist() == [x // 3]
