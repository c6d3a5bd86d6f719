"""The tiny network: shapes, gradients, batching of thresholds, split convs, AUC, sizes."""

import dataclasses

import pytest
import torch

from bittc_core.model import CONFIGS, BinaryTTCNet, count_parameters, get_config
from bittc_core.model.auc import auc_eta, uniform_levels
from bittc_core.model.correlation import scale_correlation
from bittc_core.model.network import CPU_INFERENCE_HYPOTHESES
from bittc_core.model.segnet import _broadcast_add

H, W = 48, 96


@pytest.fixture
def net():
    torch.manual_seed(0)
    return BinaryTTCNet(get_config("tiny"))


def frames(b=2, seed=0):
    g = torch.Generator().manual_seed(seed)
    return torch.rand(b, 3, H, W, generator=g), torch.rand(b, 3, H, W, generator=g)


def test_forward_backward_shapes_and_gradients(net):
    prev, latest = frames()
    b = prev.shape[0]
    feats = net.extract(torch.cat((prev, latest)))
    assert feats.shape == (2 * b, net.config.feat_channels, H // 3, W // 3)
    ctx = net.prepare_reference(feats[b:], latest)
    ttc = net.classify_eta(ctx, feats[:b], torch.tensor([[0.7, 0.9, 1.05]]).expand(b, -1))
    flow = net.classify_shift(ctx, feats[:b], torch.tensor([[[3.0, -6.0]]]).expand(b, -1, -1))
    cont = net.continuous(ctx, feats[:b])
    assert ttc.shape == (b, 3, H, W) and flow.shape == (b, 1, 2, H, W)
    assert cont.prob_le.shape == (b, net.config.cont_levels, H, W) and cont.log_eta.shape == (b, 1, H, W)
    (ttc.mean() + flow.mean() + cont.log_eta.mean()).backward()
    grads = {n: p.grad for n, p in net.named_parameters()}
    assert all(g is not None and torch.isfinite(g).all() for g in grads.values()), [
        n for n, g in grads.items() if g is None
    ]


def test_thresholds_batched_equal_one_at_a_time(net):
    net.eval()
    prev, latest = frames(b=2)
    # more thresholds than one inference batch of SegNet holds, so the chunks are covered;
    # two images with different thresholds, so a mix-up of image and threshold order shows
    k = CPU_INFERENCE_HYPOTHESES * 2 + 3
    eta = torch.stack([torch.linspace(0.7, 1.1, k), torch.linspace(1.05, 0.75, k)])
    with torch.no_grad():
        together = net(prev, latest, eta)
        alone = torch.cat([net(prev, latest, eta[:, i : i + 1]) for i in range(k)], dim=1)
    assert together.shape == (2, k, H, W)
    torch.testing.assert_close(together, alone, atol=1e-5, rtol=1e-4)


def test_split_conv_equals_conv_of_concatenation():
    torch.manual_seed(0)
    a_part, b_part = torch.nn.Conv2d(4, 6, 3, padding=1), torch.nn.Conv2d(4, 6, 3, padding=1, bias=False)
    whole = torch.nn.Conv2d(8, 6, 3, padding=1)
    with torch.no_grad():
        whole.weight.copy_(torch.cat((a_part.weight, b_part.weight), dim=1))
        whole.bias.copy_(a_part.bias)
    ref = torch.randn(2, 4, 8, 8)  # two reference frames
    warped = torch.randn(6, 4, 8, 8)  # three hypotheses each
    split = _broadcast_add(a_part(ref), b_part(warped))
    full = whole(torch.cat((ref.repeat_interleave(3, dim=0), warped), dim=1))
    torch.testing.assert_close(split, full, atol=1e-5, rtol=1e-5)


def test_auc_of_a_step_returns_its_location():
    lo, hi, k = 0.6, 1.2, 24
    levels = uniform_levels(lo, hi, k)
    step = (hi - lo) / k
    for m in (0, 5, 13, 24):  # step on a bin edge: exact
        edge = lo + m * step
        prob_le = (levels >= edge).float()[None, :, None, None]  # p(eta <= eta_i) of eta* = edge
        assert auc_eta(prob_le, lo, hi).item() == pytest.approx(edge, abs=1e-6)
    for eta_star in (0.71, 0.9333, 1.05):  # inside a bin: that bin's centre, within d/2
        prob_le = (levels >= eta_star).float()[None, :, None, None]
        assert abs(auc_eta(prob_le, lo, hi).item() - eta_star) <= step / 2 + 1e-6
    # a symmetric smooth transition centred on a level gives that level
    centre = levels[10].item()
    prob_le = torch.sigmoid((levels - centre) / 0.01)[None, :, None, None]
    assert auc_eta(prob_le, lo, hi).item() == pytest.approx(centre, abs=1e-4)


@pytest.mark.parametrize("levels", [False, True])
def test_untrained_cont_refiner_returns_the_auc(levels):
    torch.manual_seed(0)
    net = BinaryTTCNet(dataclasses.replace(get_config("tiny"), cont_refine_levels=levels)).eval()
    prev, latest = frames()
    with torch.no_grad():
        feats = net.extract(torch.cat((prev, latest)))
        cont = net.continuous(net.prepare_reference(feats[2:], latest), feats[:2])
    torch.testing.assert_close(cont.log_eta, torch.log(cont.eta_auc))
    # a refiner that reads the level maps needs all of them
    if levels:
        with pytest.raises(ValueError, match="expected 8 level maps, got 7"):
            net.cont_refine(cont.log_eta, latest, cont.prob_le[:, :7])


def test_image_size_must_be_multiple_of_three(net):
    with pytest.raises(ValueError, match="multiples of 3"):
        net.extract(torch.rand(1, 3, 50, 96))


def test_registered_config_sizes():
    with torch.device("meta"):
        paper = count_parameters(BinaryTTCNet(CONFIGS["paper"]))
        small = count_parameters(BinaryTTCNet(CONFIGS["cpu-small"]))
        gc = count_parameters(BinaryTTCNet(CONFIGS["cpu-small-gc"]))
        medium = count_parameters(BinaryTTCNet(CONFIGS["cpu-medium"]))
        corr = count_parameters(BinaryTTCNet(CONFIGS["cpu-small-corr"]))
        shift = count_parameters(BinaryTTCNet(CONFIGS["cpu-small-corr-shift"]))
        column = count_parameters(BinaryTTCNet(CONFIGS["cpu-small-corr-column"]))
        column_input = count_parameters(BinaryTTCNet(CONFIGS["cpu-small-corr-column-input"]))
        tiny = count_parameters(BinaryTTCNet(CONFIGS["tiny"]))
    assert 88e6 < paper < 94e6  # "about 91 M"
    assert tiny < small < gc < 2e6  # cpu-small-gc = cpu-small + the global-context block
    assert small < medium < 2e6  # cpu-medium = cpu-small + growth blocks
    assert corr - small == 3 * 8 * 16 * (9 + 1)  # cpu-small-corr: 3 warps x 8 groups into 16-ch 3x3 and 1x1 convs
    assert shift - corr == 3 * 8 * 16 * (9 + 1)  # the shifted correlations: as many again, their own convs
    assert column - corr == 3 * 8 * 16 * (9 + 1)  # the column correlations: the same
    assert column_input - column == 16 * 16 * 9  # the source warped by columns: one 16-ch 3x3 conv
    assert CONFIGS["paper"].norm == "none" and CONFIGS["cpu-small"].norm != "none"


@pytest.mark.parametrize(
    "field, base",
    [
        ("feat_extra_blocks", {}),
        ("dec_extra_blocks", {}),
        ("refine_extra_blocks", {}),
        ("corr_groups", {}),
        ("corr_shift_px", {"corr_groups": 2}),
        ("corr_column", {"corr_groups": 2}),
        ("corr_column", {"corr_groups": 2, "corr_shift_px": 1}),
        ("column_input", {"corr_groups": 2, "corr_column": True}),
        ("column_input", {}),
    ],
)
def test_growth_blocks_start_as_the_identity(field, base):
    """A config with added growth blocks (or the correlation volume, or its shifted
    correlations), loaded with the smaller config's weights, computes the same geofences
    and continuous output. In train mode too, except for decoder blocks: the finest level
    then runs on a wider crop, so its batch norm takes its statistics over more pixels."""
    torch.manual_seed(0)
    small = BinaryTTCNet(dataclasses.replace(CONFIGS["tiny"], **base))
    grown = BinaryTTCNet(
        dataclasses.replace(CONFIGS["tiny"], **base, **{field: True if field in ("corr_column", "column_input") else 2})
    )
    if base:  # a trained volume: live, so the grown network must keep what it adds
        with torch.no_grad():
            small.segnet.corr_first.weight.normal_(0.0, 0.3)
            if base.get("corr_column"):  # and its column correlations
                small.segnet.column_first.weight.normal_(0.0, 0.3)
                small.segnet.column_last.weight.normal_(0.0, 0.3)
    missing, unexpected = grown.load_state_dict(small.state_dict(), strict=False)
    added = (".extra", "dec_extra", ".corr_", ".shift_", ".column_")
    assert missing and not unexpected and all(any(a in k for a in added) for k in missing)
    prev, latest = torch.rand(2, 3, 48, 96), torch.rand(2, 3, 48, 96)
    eta = torch.tensor([[0.8, 1.0], [0.9, 1.1]])
    for train in (False,) if field == "dec_extra_blocks" else (True, False):
        small.train(train)
        grown.train(train)
        with torch.no_grad():
            torch.testing.assert_close(grown(prev, latest, eta), small(prev, latest, eta), rtol=0, atol=0)
    small.eval()
    grown.eval()
    with torch.no_grad():
        outs = []
        for n in (small, grown):
            feats = n.extract(torch.cat((prev, latest)))
            outs.append(n.continuous(n.prepare_reference(feats[2:], latest), feats[:2]).log_eta)
    torch.testing.assert_close(outs[1], outs[0], rtol=0, atol=0)


def test_growth_counts_must_not_be_negative():
    with pytest.raises(ValueError, match="dec_extra_blocks=-1"):
        dataclasses.replace(CONFIGS["tiny"], dec_extra_blocks=-1)


def test_correlation_groups_must_divide_the_features():
    with pytest.raises(ValueError, match="corr_groups=3: must divide feat_channels=8"):
        dataclasses.replace(CONFIGS["tiny"], corr_groups=3)
    for step in (0.0, float("nan")):
        with pytest.raises(ValueError, match=f"corr_log_step={step}"):
            dataclasses.replace(CONFIGS["tiny"], corr_groups=2, corr_log_step=step)


def test_the_column_input_is_the_column_warp_read_through_its_own_convs():
    """The volume's centre column correlation reads SegNet's second input (the source
    warped by columns) instead of warping again, with the same result; each of the input's
    two convs (the finest one with ``full_res_skip``) reaches the logits."""
    torch.manual_seed(0)
    cfg = dataclasses.replace(CONFIGS["tiny"], corr_groups=2, corr_column=True, column_input=True)
    net = BinaryTTCNet(cfg).eval()
    prev, latest = torch.rand(1, 3, 48, 96), torch.rand(1, 3, 48, 96)
    eta = torch.tensor([[0.8, 0.95]])
    with torch.no_grad():
        feats = net.extract(torch.cat((prev, latest)))
        ctx = net.prepare_reference(feats[1:], latest)
        inputs = net.scale_inputs(ctx.terms.feat, feats[:1], eta, ctx.grid)
        unshared = scale_correlation(
            ctx.terms.feat, feats[:1], eta, inputs.warped, ctx.grid, 2, cfg.corr_log_step, 0, True
        )
        torch.testing.assert_close(inputs.corr, unshared, rtol=0, atol=0)
        base = net(prev, latest, eta)
        for name in ("column_src_first", "column_src_last"):
            layer = getattr(net.segnet, name)
            layer.weight.normal_(0.0, 0.3)
            assert not torch.allclose(net(prev, latest, eta), base), name
            layer.weight.zero_()
        torch.testing.assert_close(net(prev, latest, eta), base, rtol=0, atol=0)
        # the flow heads read no column input; a network without it refuses one
        assert net.classify_shift(ctx, feats[:1], torch.tensor([[[3.0, 0.0]]])).shape[:3] == (1, 1, 2)
        plain = BinaryTTCNet(dataclasses.replace(cfg, column_input=False)).eval()
        with pytest.raises(ValueError, match="column_warped given to a network without the column input"):
            plain.segnet(ctx.terms, inputs, ctx.grid)
