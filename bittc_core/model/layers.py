"""Small building blocks shared by the network files."""

from __future__ import annotations

import math

from torch import nn

LEAKY_SLOPE = 0.1  # LeakyReLU slope used throughout (paper, Supp. A)


def make_norm(norm: str, channels: int) -> nn.Module:
    """ "none" -> identity, "batch" -> BatchNorm2d, "group" -> GroupNorm (<= 8 groups)."""
    if norm == "none":
        return nn.Identity()
    if norm == "batch":
        return nn.BatchNorm2d(channels)
    if norm == "group":
        return nn.GroupNorm(math.gcd(8, channels), channels)
    raise ValueError(f"unknown norm {norm!r}")


def conv(
    in_ch: int,
    out_ch: int,
    kernel: int = 3,
    stride: int = 1,
    dilation: int = 1,
    bias: bool = True,
    padding: int | None = None,
) -> nn.Conv2d:
    """A convolution, 'same'-padded (odd kernels) unless ``padding`` is given."""
    pad = dilation * (kernel // 2) if padding is None else padding
    return nn.Conv2d(in_ch, out_ch, kernel, stride=stride, padding=pad, dilation=dilation, bias=bias)


class ConvNormAct(nn.Sequential):
    """conv -> norm -> LeakyReLU(0.1); the conv has a bias only when there is no norm."""

    def __init__(
        self,
        in_ch: int,
        out_ch: int,
        *,
        kernel: int = 3,
        stride: int = 1,
        dilation: int = 1,
        norm: str = "none",
        act: bool = True,
        padding: int | None = None,
    ) -> None:
        super().__init__(
            conv(in_ch, out_ch, kernel, stride, dilation, bias=norm == "none", padding=padding),
            make_norm(norm, out_ch),
            nn.LeakyReLU(LEAKY_SLOPE, inplace=True) if act else nn.Identity(),
        )


class NormAct(nn.Sequential):
    """norm -> LeakyReLU(0.1), for sums of split convolutions."""

    def __init__(self, channels: int, norm: str) -> None:
        super().__init__(make_norm(norm, channels), nn.LeakyReLU(LEAKY_SLOPE, inplace=True))


class GrowthBlock(nn.Module):
    """x + body(x), body = conv -> norm -> LeakyReLU -> conv -> norm, the identity at init.

    Its last layer starts at zero (the norm's scale and shift, or the conv's weight and
    bias when there is no norm), and nothing follows the sum, so a block added to a
    trained network leaves that network's output unchanged until training moves it
    (the ``*_extra_blocks`` fields of ``ModelConfig``)."""

    def __init__(self, channels: int, norm: str) -> None:
        super().__init__()
        last_conv = conv(channels, channels, bias=norm == "none")
        last_norm = make_norm(norm, channels)
        self.body = nn.Sequential(ConvNormAct(channels, channels, norm=norm), last_conv, last_norm)
        zero = last_conv if norm == "none" else last_norm
        nn.init.zeros_(zero.weight)
        nn.init.zeros_(zero.bias)

    def forward(self, x):
        return x + self.body(x)


def growth_blocks(channels: int, norm: str, count: int) -> nn.Sequential:
    """``count`` ``GrowthBlock`` in a row (an empty Sequential, the identity, for 0)."""
    return nn.Sequential(*[GrowthBlock(channels, norm) for _ in range(count)])
