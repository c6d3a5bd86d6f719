"""The streaming network as four exportable graphs, each an ``nn.Module`` over plain tensors.

The split is the estimator's cost split (``bittc_core.model.network``):

============  ===============================================  ==============================
graph         inputs -> outputs                                runs
============  ===============================================  ==============================
extractor     image (V, 3, H, W) -> features (V, C, h, w)       once per frame (cache it)
reference     features, image of the latest frame ->            once per latest frame
              the hypothesis-independent terms (``REF_NAMES``)
thresholds    reference terms, features_prev, eta (V, K) ->    once per call, K dynamic
              logits (V, K, H, W) of p(eta <= eta_i)
continuous    reference terms, image_latest, features_prev ->  once per continuous call
              log_eta (V, 1, H, W), refined
============  ===============================================  ==============================

V is the number of views (1; 2 with flip averaging), h, w = H / 3, W / 3. Images are RGB
float32 in [0, 1]; the graphs normalise them ((x - 0.5) / 0.5) themselves. The image size
is fixed at export (the padded grid of the warps depends on it); V and K are dynamic.

``thresholds`` classifies all K hypotheses of a call in one batch (SegNet and the
refiner), where the torch estimator loops over chunks and over maps for the CPU's caches;
in eval mode the two compute the same function (batch norm uses its running statistics).
"""

from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import nn

from bittc_core.model import BinaryTTCNet
from bittc_core.model.auc import auc_eta, uniform_levels
from bittc_core.model.network import FEATURE_STRIDE
from bittc_core.model.segnet import HEAD_TTC, ReferenceTerms
from bittc_core.model.warp import PaddedGrid

GRAPHS = ("extractor", "reference", "thresholds", "continuous")


def padded_grid(net: BinaryTTCNet, height_px: int, width_px: int) -> PaddedGrid:
    c = net.config
    return PaddedGrid.for_features(height_px // FEATURE_STRIDE, width_px // FEATURE_STRIDE, c.pad_factor, c.down_factor)


def reference_names(net: BinaryTTCNet) -> tuple[str, ...]:
    """The reference terms this config has, in the graphs' order."""
    c = net.config
    return (
        ("ref_first",)
        + (("ref_skip",) if c.full_res_skip else ())
        + (("ref_feat",) if c.corr_groups else ())
        + ("guide",)
    )


class _Graph(nn.Module):
    def __init__(self, net: BinaryTTCNet, height_px: int, width_px: int) -> None:
        super().__init__()
        self.net = net.eval()
        self.size = (height_px, width_px)
        self.grid = padded_grid(net, height_px, width_px)
        self.ref_names = reference_names(net)

    def _terms(self, refs: tuple[torch.Tensor, ...]) -> tuple[ReferenceTerms, torch.Tensor]:
        d = dict(zip(self.ref_names, refs))
        return ReferenceTerms(first=d["ref_first"], skip=d.get("ref_skip"), feat=d.get("ref_feat")), d["guide"]

    def _logits(self, refs: tuple[torch.Tensor, ...], feat_prev: torch.Tensor, eta: torch.Tensor) -> torch.Tensor:
        """eta (V, K) -> refined logits (V, K, H, W), all hypotheses in one batch."""
        net, grid = self.net, self.grid
        terms, guide = self._terms(refs)
        v, k = eta.shape
        inputs = net.scale_inputs(terms.feat, feat_prev, eta, grid)
        coarse = net.segnet(terms, inputs, grid)[:, HEAD_TTC : HEAD_TTC + 1]
        coarse = F.interpolate(coarse, size=self.size, mode="bilinear", align_corners=False)
        return net.refine(guide, coarse).view(v, k, *self.size)


class ExtractorGraph(_Graph):
    def forward(self, image: torch.Tensor) -> torch.Tensor:
        return self.net.extract(image)


class ReferenceGraph(_Graph):
    def forward(self, features: torch.Tensor, image: torch.Tensor) -> tuple[torch.Tensor, ...]:
        terms = self.net.segnet.prepare(self.grid.pad(features), self.grid)
        out = {
            "ref_first": terms.first,
            "ref_skip": terms.skip,
            "ref_feat": terms.feat,
            "guide": self.net.refine.guide(image),
        }
        return tuple(out[n] for n in self.ref_names)


class ThresholdsGraph(_Graph):
    def forward(self, *args: torch.Tensor) -> torch.Tensor:
        *refs, feat_prev, eta = args
        return self._logits(tuple(refs), feat_prev, eta)


class ContinuousGraph(_Graph):
    def forward(self, *args: torch.Tensor) -> torch.Tensor:
        *refs, image_latest, feat_prev = args
        c = self.net.config
        levels = uniform_levels(c.cont_eta_min, c.cont_eta_max, c.cont_levels, device=feat_prev.device)
        eta = levels[None].expand(feat_prev.shape[0], -1)
        prob_le = torch.sigmoid(self._logits(tuple(refs), feat_prev, eta))
        eta_auc = auc_eta(prob_le, c.cont_eta_min, c.cont_eta_max)
        return self.net.cont_refine(torch.log(eta_auc), image_latest, prob_le)
