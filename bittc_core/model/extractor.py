"""FeatExtractNet: PSMNet-style features at 1/3 of the input resolution.

stem (3x3 conv, stride 3) -> 3x3 conv -> residual blocks (then ``extra_blocks`` growth
blocks, the identity at init) -> spatial pyramid pooling
(average pools of several windows, 1x1 conv, bilinear upsampling) -> fusion conv.

Convention: input (B, 3, H, W) in [0, 1] with H, W multiples of 3; the net normalises
with mean 0.5 and std 0.5 itself. Output (B, C, H/3, W/3); feature pixel (i, j) covers
input pixels 3i..3i+2 x 3j..3j+2, so its centre is input pixel (3i+1, 3j+1) and the
image centre (H-1)/2, (W-1)/2 maps to the feature-map centre.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import nn

from bittc_core.model.layers import LEAKY_SLOPE, ConvNormAct, conv, growth_blocks, make_norm

IMAGE_MEAN = 0.5
IMAGE_STD = 0.5


class ResBlock(nn.Module):
    """x + conv(act(conv(x))), then LeakyReLU."""

    def __init__(self, channels: int, norm: str) -> None:
        super().__init__()
        self.body = nn.Sequential(
            ConvNormAct(channels, channels, norm=norm),
            conv(channels, channels, bias=norm == "none"),
            make_norm(norm, channels),
        )
        self.act = nn.LeakyReLU(LEAKY_SLOPE, inplace=True)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.act(x + self.body(x))


class FeatExtractNet(nn.Module):
    def __init__(
        self,
        *,
        stem_channels: int,
        out_channels: int,
        res_blocks: int,
        pool_sizes: tuple[int, ...],
        spp_channels: int,
        norm: str,
        extra_blocks: int = 0,
    ) -> None:
        super().__init__()
        self.stem = nn.Sequential(
            # no padding: feature pixel i sees input pixels 3i..3i+2 exactly (centre 3i+1)
            ConvNormAct(3, stem_channels, kernel=3, stride=3, norm=norm, padding=0),
            ConvNormAct(stem_channels, stem_channels, norm=norm),
        )
        self.blocks = nn.Sequential(*[ResBlock(stem_channels, norm) for _ in range(res_blocks)])
        self.extra = growth_blocks(stem_channels, norm, extra_blocks)
        self.pool_sizes = pool_sizes
        self.branches = nn.ModuleList(
            [ConvNormAct(stem_channels, spp_channels, kernel=1, norm=norm) for _ in pool_sizes]
        )
        fused = stem_channels * 2 + spp_channels * len(pool_sizes)
        self.fuse = nn.Sequential(
            ConvNormAct(fused, out_channels, norm=norm),
            nn.Conv2d(out_channels, out_channels, 1),
        )

    def forward(self, images: torch.Tensor) -> torch.Tensor:
        x = (images - IMAGE_MEAN) / IMAGE_STD
        low = self.stem(x)
        high = self.extra(self.blocks(low))
        size = high.shape[-2:]
        pyramid = [low, high]
        for window, branch in zip(self.pool_sizes, self.branches):
            # windows larger than the map collapse to a global pool
            k = (min(window, size[0]), min(window, size[1]))
            pooled = branch(F.avg_pool2d(high, k, stride=k))
            pyramid.append(F.interpolate(pooled, size=size, mode="bilinear", align_corners=False))
        return self.fuse(torch.cat(pyramid, dim=1))
