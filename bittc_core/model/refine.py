"""SegRefineNet: refines each binary logit map guided by the reference image.

Guide features: three 3x3 convs on the (normalised) reference image, ReLU, ReLU, none
(paper Supp. A). They do not depend on the threshold, so ``guide`` runs once per frame
and, with the first refine conv split as conv([logit, g]) = conv_l(logit) + conv_g(g),
the guide part of that conv is also computed once. Per map: that sum, LeakyReLU, then
``layers - 1`` 3x3 convs with LeakyReLU(0.1), ``extra_blocks`` growth blocks (the
identity at init, not in the paper) and a last 3x3 conv. We add its output to
the coarse logit (a residual, our choice) so an untrained refiner starts as identity-ish.
"""

from __future__ import annotations

import torch
from torch import nn

from bittc_core.model.extractor import IMAGE_MEAN, IMAGE_STD
from bittc_core.model.layers import LEAKY_SLOPE, conv, growth_blocks
from bittc_core.model.segnet import _broadcast_add


class SegRefineNet(nn.Module):
    def __init__(self, *, guide_channels: int, channels: int, layers: int, extra_blocks: int = 0) -> None:
        super().__init__()
        g = guide_channels
        self.guide_net = nn.Sequential(
            conv(3, g),
            nn.ReLU(inplace=True),
            conv(g, g),
            nn.ReLU(inplace=True),
            conv(g, g),
        )
        self.first_guide = conv(g, channels)
        self.first_logit = conv(1, channels, bias=False)
        body: list[nn.Module] = [nn.LeakyReLU(LEAKY_SLOPE, inplace=True)]
        for _ in range(layers - 1):
            body += [conv(channels, channels), nn.LeakyReLU(LEAKY_SLOPE, inplace=True)]
        body.append(conv(channels, 1))
        self.body = nn.Sequential(*body)  # indices kept as before growth, for checkpoints
        self.extra = growth_blocks(channels, "none", extra_blocks)

    def guide(self, image_ref: torch.Tensor) -> torch.Tensor:
        """(B, 3, H, W) in [0, 1] -> guide part of the first refine conv (B, ch, H, W)."""
        return self.first_guide(self.guide_net((image_ref - IMAGE_MEAN) / IMAGE_STD))

    def forward(self, guide_terms: torch.Tensor, logit: torch.Tensor) -> torch.Tensor:
        """logit (B*K, 1, H, W) -> refined logit (B*K, 1, H, W)."""
        x = _broadcast_add(guide_terms, self.first_logit(logit))
        *hidden, last = self.body
        for layer in hidden:
            x = layer(x)
        return logit + last(self.extra(x))
