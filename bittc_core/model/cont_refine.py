"""ContRefineNet: StereoNet-style refinement of the AUC motion-in-depth map.

Input: log(eta_auc) (B, 1, H, W) and the reference image (B, 3, H, W) in [0, 1].
A 3x3 conv, residual blocks with dilations ``dilations`` (two 3x3 convs each), and a
3x3 conv that predicts a residual in log eta: log eta = log eta_auc + delta. Working in
log eta keeps eta positive and makes an error of x % equally costly at every eta.
"""

from __future__ import annotations

import torch
from torch import nn

from bittc_core.model.extractor import IMAGE_MEAN, IMAGE_STD
from bittc_core.model.layers import LEAKY_SLOPE, ConvNormAct, conv, make_norm


class DilatedResBlock(nn.Module):
    def __init__(self, channels: int, dilation: int, norm: str) -> None:
        super().__init__()
        self.body = nn.Sequential(
            ConvNormAct(channels, channels, dilation=dilation, norm=norm),
            conv(channels, channels, dilation=dilation, bias=norm == "none"),
            make_norm(norm, channels),
        )
        self.act = nn.LeakyReLU(LEAKY_SLOPE, inplace=True)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.act(x + self.body(x))


class ContRefineNet(nn.Module):
    def __init__(self, *, channels: int, dilations: tuple[int, ...], norm: str) -> None:
        super().__init__()
        self.stem = ConvNormAct(4, channels, norm=norm)
        self.blocks = nn.Sequential(*[DilatedResBlock(channels, d, norm) for d in dilations])
        self.out = conv(channels, 1)

    def forward(self, log_eta: torch.Tensor, image_ref: torch.Tensor) -> torch.Tensor:
        """-> refined log eta (B, 1, H, W)."""
        x = torch.cat((log_eta, (image_ref - IMAGE_MEAN) / IMAGE_STD), dim=1)
        return log_eta + self.out(self.blocks(self.stem(x)))
