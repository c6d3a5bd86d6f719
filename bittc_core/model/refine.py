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

#: up to this many input elements torch runs a 3x3 conv of batch 1 on its native path
#: (aten ``use_mkldnn``), which is ~10x slower when the weight has channels-last strides
_NATIVE_CONV_MAX_ELEMENTS = 20480


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

    def _logit_term(self, logit: torch.Tensor) -> torch.Tensor:
        """``first_logit`` of (N, 1, H, W). Its (C, 1, 3, 3) weight is contiguous in either
        memory layout; on a CPU a small map (the fovea's 96x144) takes torch's native conv
        path, which is fast only with plain strides (0.05 against 0.49 ms, 2 threads), and
        a large one oneDNN's, fast with the channels-last strides of a channels-last
        network: so a single small map gets a plain-strided view of the 72 weights (not in
        a traced or exported graph, whose sizes are symbols and whose runtime picks its own
        kernels)."""
        w = self.first_logit.weight
        if (
            not torch.compiler.is_compiling()
            and logit.device.type == "cpu"
            and logit.shape[0] == 1
            and logit.numel() <= _NATIVE_CONV_MAX_ELEMENTS
        ):
            w = w.view(w.shape[0], -1).view(w.shape)  # the same weights with plain strides (no copy)
        return self.first_logit._conv_forward(logit, w, None)

    def forward(self, guide_terms: torch.Tensor, logit: torch.Tensor) -> torch.Tensor:
        """logit (B*K, 1, H, W) -> refined logit (B*K, 1, H, W)."""
        x = _broadcast_add(guide_terms, self._logit_term(logit))
        *hidden, last = self.body
        for layer in hidden:
            x = layer(x)
        return logit + last(self.extra(x))
