"""ContRefineNet: StereoNet-style refinement of the AUC motion-in-depth map.

Input: log(eta_auc) (B, 1, H, W) and the reference image (B, 3, H, W) in [0, 1]; with
``levels`` > 0 also the K = ``levels`` maps p(eta <= eta_i) (B, K, H, W) the AUC summed
(not in the paper: the shape of the per-pixel CDF tells where inside a bin eta lies,
which its sum alone does not). A 3x3 conv, residual blocks with dilations ``dilations``
(two 3x3 convs each), and a 3x3 conv that predicts a residual in log eta:
log eta = log eta_auc + delta. Working in log eta keeps eta positive and makes an error
of x % equally costly at every eta. The residual conv starts at zero, so an untrained
refiner returns the AUC unchanged and training starts from the AUC's error.
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
    def __init__(self, *, channels: int, dilations: tuple[int, ...], norm: str, levels: int = 0) -> None:
        super().__init__()
        self.levels = levels
        self.stem = ConvNormAct(4 + levels, channels, norm=norm)
        self.blocks = nn.Sequential(*[DilatedResBlock(channels, d, norm) for d in dilations])
        self.out = conv(channels, 1)
        nn.init.zeros_(self.out.weight)
        nn.init.zeros_(self.out.bias)

    def forward(
        self, log_eta: torch.Tensor, image_ref: torch.Tensor, prob_le: torch.Tensor | None = None
    ) -> torch.Tensor:
        """-> refined log eta (B, 1, H, W)."""
        parts = [log_eta, (image_ref - IMAGE_MEAN) / IMAGE_STD]
        if self.levels:
            if prob_le is None or prob_le.shape[1] != self.levels:
                got = None if prob_le is None else prob_le.shape[1]
                raise ValueError(f"ContRefineNet: expected {self.levels} level maps, got {got}")
            parts.append(prob_le - 0.5)
        return log_eta + self.out(self.blocks(self.stem(torch.cat(parts, dim=1))))
