"""SegNet2D: encoder-decoder with skip connections over [f_ref, P_phi(f_src)].

Encoder: blocks of (3x3 conv stride 2, 3x3 conv), one /2 per block. Decoder: blocks of
(4x4 deconv stride 2, 3x3 conv over [upsampled, skip]); the skip of the finest block
is the input volume itself (``full_res_skip``). A final 3x3 conv gives three logits per
pixel: binary TTC, binary flow u, binary flow v (paper Supp. A). ``extra_blocks`` growth
blocks (identity at init, not in the paper) follow each decoder level's last conv.

Split convolutions (field notes): a conv over a channel concatenation is the sum of
convs over the parts, conv([a, b]) = conv_a(a) + conv_b(b). The reference part of the
first encoder conv (and of the full-resolution skip conv) does not depend on the
hypothesis, so ``prepare`` computes it once per frame pair and ``forward`` adds it to
the warped part of every hypothesis (broadcast, no copy).

Global context (``global_context``, not in the paper): the bottleneck map of each
hypothesis is averaged over the padded map, passed through two 1x1 convs and added
back at every position. The idea: a local decision cannot tell a textureless road of a
standing ego (tau = inf) from one of a moving ego (tau = Z / v_ego), the average could
carry what the whole image says. The second conv starts at zero, so the block starts as
the identity and can be added to a trained network (``checkpoint.init_network``).
Added to the trained ``cpu-small`` and fine-tuned, it was not measurably used (README).
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
import torch.nn.functional as F
from torch import nn

from bittc_core.model.layers import LEAKY_SLOPE, ConvNormAct, NormAct, conv, growth_blocks, make_norm
from bittc_core.model.warp import PaddedGrid

NUM_HEADS = 3  # ttc, flow u, flow v
HEAD_TTC, HEAD_U, HEAD_V = 0, 1, 2


@dataclass
class ReferenceTerms:
    """Hypothesis-independent partial sums, each (B, C, h, w)."""

    first: torch.Tensor
    skip: torch.Tensor | None
    feat: torch.Tensor | None  # the unpadded reference features, kept for the correlation


@dataclass
class SegNetInputs:
    """What SegNet reads for B*K hypotheses (``SegNet2D.forward``)."""

    warped: torch.Tensor  # (B*K, C, hp, wp) the source warped by the hypothesis
    corr: torch.Tensor | None = None  # (B*K, n, h, w) the correlation volume, unpadded
    column_warped: torch.Tensor | None = None  # (B*K, C, hp, wp) the source warped by columns


@dataclass(frozen=True)
class _MarginBox:
    """The unpadded map of a ``PaddedGrid`` grown by up to ``margin`` px a side."""

    top: int
    left: int
    bottom: int  # exclusive
    right: int  # exclusive
    inner_top: int
    inner_left: int
    h: int
    w: int

    @classmethod
    def around(cls, grid: PaddedGrid, margin: int) -> _MarginBox:
        top, left = max(grid.top - margin, 0), max(grid.left - margin, 0)
        bottom = min(grid.top + grid.h + margin, grid.hp)
        right = min(grid.left + grid.w + margin, grid.wp)
        return cls(top, left, bottom, right, grid.top - top, grid.left - left, grid.h, grid.w)

    def cut(self, x: torch.Tensor) -> torch.Tensor:
        return x[..., self.top : self.bottom, self.left : self.right]

    def inner(self, x: torch.Tensor) -> torch.Tensor:
        return x[..., self.inner_top : self.inner_top + self.h, self.inner_left : self.inner_left + self.w]


def _broadcast_add(ref: torch.Tensor, per_hyp: torch.Tensor) -> torch.Tensor:
    """ref (B, C, h, w) + per_hyp (B*K, C, h, w) -> (B*K, C, h, w) without repeating ref."""
    b = ref.shape[0]
    k = per_hyp.shape[0] // b
    out = per_hyp.view(b, k, *per_hyp.shape[1:]) + ref[:, None]
    return out.view(b * k, *per_hyp.shape[1:])


def _pad_to(x: torch.Tensor, top: int, left: int, size_hw: tuple[int, int]) -> torch.Tensor:
    """Place (N, C, h, w) at (top, left) of a zero (N, C, H, W) map, cropping what falls outside."""
    h, w = size_hw
    x = x[..., : h - top, : w - left]
    return F.pad(x, (left, w - left - x.shape[-1], top, h - top - x.shape[-2]))


class GlobalContext(nn.Module):
    """x (N, C, h, w) -> x + expand(LeakyReLU(reduce(mean_hw(x)))), identity at init."""

    def __init__(self, channels: int) -> None:
        super().__init__()
        hidden = max(channels // 2, 4)
        self.reduce = nn.Conv2d(channels, hidden, 1)
        self.expand = nn.Conv2d(hidden, channels, 1)
        nn.init.zeros_(self.expand.weight)
        nn.init.zeros_(self.expand.bias)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        g = F.leaky_relu(self.reduce(x.mean(dim=(2, 3), keepdim=True)), LEAKY_SLOPE)
        return x + self.expand(g)


def _zero_start_convs(
    channels: int, first_out: int, last_out: int, last_kernel: int = 1, with_last: bool = True
) -> tuple[nn.Module | None, nn.Module | None]:
    """A 3x3 stride-2 conv (into the first encoder conv) and, ``with_last``, a ``last_kernel``
    conv (into the finest decoder conv; else None) of ``channels`` input channels, without
    bias and zero at init, so that adding them leaves a trained network unchanged; (None,
    None) for no channels."""
    if not channels:
        return None, None
    first = conv(channels, first_out, stride=2, bias=False)
    last = conv(channels, last_out, kernel=last_kernel, bias=False) if with_last else None
    for layer in (first, last):
        if layer is not None:
            nn.init.zeros_(layer.weight)
    return first, last


class SegNet2D(nn.Module):
    def __init__(
        self,
        *,
        feat_channels: int,
        enc_channels: tuple[int, ...],
        dec_channels: tuple[int, ...],
        full_res_skip: bool,
        norm: str,
        global_context: bool = False,
        extra_blocks: int = 0,
        corr_channels: int = 0,
        shift_channels: int = 0,
        column_channels: int = 0,
        column_input: bool = False,
    ) -> None:
        super().__init__()
        e, d = enc_channels, dec_channels
        levels = len(e)
        has_bias = norm == "none"
        self.first_ref = conv(feat_channels, e[0], stride=2, bias=has_bias)
        self.first_src = conv(feat_channels, e[0], stride=2, bias=False)
        self.first_post = NormAct(e[0], norm)
        self.first_conv2 = ConvNormAct(e[0], e[0], norm=norm)
        self.down = nn.ModuleList(
            nn.Sequential(ConvNormAct(e[i - 1], e[i], stride=2, norm=norm), ConvNormAct(e[i], e[i], norm=norm))
            for i in range(1, levels)
        )
        self.context = GlobalContext(e[-1]) if global_context else None
        self.up = nn.ModuleList()
        self.fuse = nn.ModuleList()
        prev = e[-1]
        for i in range(levels):
            self.up.append(
                nn.Sequential(
                    nn.ConvTranspose2d(prev, d[i], 4, stride=2, padding=1, bias=has_bias),
                    make_norm(norm, d[i]),
                    nn.LeakyReLU(LEAKY_SLOPE, inplace=True),
                )
            )
            if i < levels - 1:
                self.fuse.append(ConvNormAct(d[i] + e[levels - 2 - i], d[i], norm=norm))
            prev = d[i]
        # finest block: conv over [upsampled, (f_ref, warped f_src)] split in parts
        self.full_res_skip = full_res_skip
        self.last_dec = conv(d[-1], d[-1], bias=has_bias)
        if full_res_skip:
            self.last_ref = conv(feat_channels, d[-1], bias=False)
            self.last_src = conv(feat_channels, d[-1], bias=False)
        self.last_post = NormAct(d[-1], norm)
        self.dec_extra = nn.ModuleList(growth_blocks(ch, norm, extra_blocks) for ch in d)
        self.head = conv(d[-1], NUM_HEADS)
        # correlation volume (``model.correlation``): a 3x3 stride-2 conv of it added to
        # the first encoder conv, a 1x1 conv to the finest decoder conv; both zero at init,
        # so a trained network is unchanged. The volume's shifted and column correlations
        # follow its channels in that order, with convs of their own, so that each can be
        # added to a trained network (zero at init)
        self.corr_first, self.corr_last = _zero_start_convs(corr_channels, e[0], d[-1])
        self.shift_first, self.shift_last = _zero_start_convs(shift_channels, e[0], d[-1])
        self.column_first, self.column_last = _zero_start_convs(column_channels, e[0], d[-1])
        widths = (("corr", corr_channels), ("shift", shift_channels), ("column", column_channels))
        self.volume_parts = tuple((name, width) for name, width in widths if width)
        # the source warped by columns (``model.warp.column_warp``), a second input beside
        # the centre-warped one: its own convs into the same two places, zero at init
        self.column_src_first, self.column_src_last = None, None
        if column_input:
            self.column_src_first, self.column_src_last = _zero_start_convs(
                feat_channels, e[0], d[-1], last_kernel=3, with_last=full_res_skip
            )

    def _volume_slices(self, corr: torch.Tensor):
        """(first conv, last conv, the part's channels of ``corr``) per part of the volume."""
        start = 0
        for name, width in self.volume_parts:
            yield getattr(self, f"{name}_first"), getattr(self, f"{name}_last"), corr[:, start : start + width]
            start += width

    def prepare(self, ref_padded: torch.Tensor, grid: PaddedGrid) -> ReferenceTerms:
        """Once per reference frame: the reference parts of the split convs."""
        skip = self.last_ref(ref_padded) if self.full_res_skip else None
        feat = grid.crop(ref_padded) if self.corr_first is not None else None
        return ReferenceTerms(first=self.first_ref(ref_padded), skip=skip, feat=feat)

    def _corr_first(self, corr: torch.Tensor, grid: PaddedGrid, size_hw: tuple[int, int]) -> torch.Tensor:
        """The first convs of the volume's parts (``corr_first``, ``shift_first``, ``column_first``)."""
        return sum(self._padded_first(first, part, grid, size_hw) for first, _, part in self._volume_slices(corr))

    def _corr_last(self, corr: torch.Tensor, box: _MarginBox, size_hw: tuple[int, int]) -> torch.Tensor:
        """The last convs of the volume's parts (1x1, no bias) on the zero-padded volume cut
        to ``box``: the convs of the map, zero-padded into the box."""
        out = sum(last(part) for _, last, part in self._volume_slices(corr))
        return _pad_to(out, box.inner_top, box.inner_left, size_hw)

    @staticmethod
    def _padded_first(layer: nn.Module, corr: torch.Tensor, grid: PaddedGrid, size_hw: tuple[int, int]) -> torch.Tensor:
        """``layer`` (3x3, stride 2, zero padding 1) of the zero-padded volume, from the
        unpadded one: the conv runs on the map with one zero row and column after it and,
        where the map starts at an odd padded row (column), one before it, so that its
        outputs fall on the padded grid's even rows (columns); every output it leaves out
        sees only zeros."""
        pt, pl = grid.top % 2, grid.left % 2
        out = layer(F.pad(corr, (pl, 1, pt, 1)))
        return _pad_to(out, (grid.top - pt) // 2, (grid.left - pl) // 2, size_hw)

    def forward(self, ref: ReferenceTerms, inputs: SegNetInputs, grid: PaddedGrid) -> torch.Tensor:
        """``inputs.warped`` (B*K, C, hp, wp) -> logits (B*K, 3, h, w), cropped to the unpadded map.
        ``inputs.column_warped`` (B*K, C, hp, wp): the source warped by columns, read where the
        config has the second input and the hypothesis is a scale (as ``corr``).
        ``inputs.corr`` (B*K, 3G, 6G or 9G, h, w): the correlation volume on the unpadded map, when the config
        has one and the hypothesis is a scale (the binary-flow heads run without it). It
        is zero in the padding, so its convs (no bias) run on the map alone and their
        outputs are zero-padded into place (``_corr_first``, ``_corr_last``): their result on
        the padded volume, up to float rounding.

        The finest level's convs only run on the crop plus a margin of 1 px per 3x3 conv:
        the result inside is exactly that of running them on the whole padded map (the
        margin covers their receptive field; beyond the padded map both see zeros)."""
        warped, corr, column_warped = inputs.warped, inputs.corr, inputs.column_warped
        if column_warped is not None and self.column_src_first is None:
            raise ValueError("SegNet2D: column_warped given to a network without the column input (column_input=False)")
        first = self.first_src(warped)
        if corr is not None:
            first = first + self._corr_first(corr, grid, first.shape[-2:])
        if column_warped is not None:
            first = first + self.column_src_first(column_warped)
        x = self.first_post(_broadcast_add(ref.first, first))
        skips = [self.first_conv2(x)]
        for block in self.down:
            skips.append(block(skips[-1]))
        x = skips.pop()
        if self.context is not None:
            x = self.context(x)
        for i, up in enumerate(self.up):
            x = up(x)
            if i < len(self.fuse):
                x = self.dec_extra[i](self.fuse[i](torch.cat((x, skips.pop()), dim=1)))
        finest_extra = self.dec_extra[-1]
        box = _MarginBox.around(grid, margin=2 + 2 * len(finest_extra))
        x = self.last_dec(box.cut(x))
        if corr is not None:
            x = x + self._corr_last(corr, box, x.shape[-2:])
        if self.full_res_skip:
            x = _broadcast_add(box.cut(ref.skip), x + self.last_src(box.cut(warped)))
            if column_warped is not None:
                x = x + self.column_src_last(box.cut(column_warped))
        return box.inner(self.head(finest_extra(self.last_post(x))))
