"""BinaryTTCNet: the composition of FeatExtractNet, warp, SegNet2D and the refiners.

Convention: ``image_prev`` (t0) is the source (warped), ``image_latest`` (t1) the
reference; every output lives in the latest frame's pixel grid. Images are
(B, 3, H, W) in [0, 1], H and W multiples of 3 px.

Outputs are logits of
    * TTC head:  P_i = p(eta <= eta_i) = p(0 < tau <= tau_i) (the geofence; the paper's
      B_tau = p(tau > tau_i) is its complement 1 - P_i),
    * flow heads: p(u > u_i), p(v > v_i) with (u, v) [px] the displacement from the
      previous to the latest position (x_prev = x_latest - (u, v)).

Cost split for streaming and for many thresholds: ``extract`` runs once per frame
(cache it), ``prepare_reference`` once per (reference frame) and the classify calls
once per batch of hypotheses, the hypotheses stacked along the batch dimension (at
inference on a CPU in SegNet batches of ``CPU_INFERENCE_HYPOTHESES``).
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
import torch.nn.functional as F
from torch import nn

from bittc_core.model.auc import auc_eta, uniform_levels
from bittc_core.model.config import ModelConfig
from bittc_core.model.cont_refine import ContRefineNet
from bittc_core.model.correlation import CORR_OFFSETS, scale_correlation
from bittc_core.model.extractor import FeatExtractNet
from bittc_core.model.refine import SegRefineNet
from bittc_core.model.segnet import HEAD_TTC, HEAD_U, HEAD_V, ReferenceTerms, SegNet2D, SegNetInputs
from bittc_core.model.warp import PaddedGrid, column_warp, scale_warp, shift_warp

FEATURE_STRIDE = 3  # [input px per feature px]
# hypotheses per SegNet batch at inference on a CPU: on 2 cores at 96x288, 24 thresholds
# in one batch cost 74 ms, in batches of 8 58 ms (4: 66 ms, 12: 70 ms), interleaved
# timing; on a GPU one batch keeps the device busy, so there all go at once
CPU_INFERENCE_HYPOTHESES = 8


@dataclass
class ReferenceContext:
    """Everything about the reference (latest) frame that no hypothesis changes."""

    image: torch.Tensor  # (B, 3, H, W)
    grid: PaddedGrid
    terms: ReferenceTerms
    guide: torch.Tensor  # (B, refine_ch, H, W)


@dataclass
class ContinuousOutput:
    levels: torch.Tensor  # (K,) eta bin centres
    prob_le: torch.Tensor  # (B, K, H, W) p(eta <= eta_i)
    eta_auc: torch.Tensor  # (B, 1, H, W) AUC estimate
    log_eta: torch.Tensor  # (B, 1, H, W) refined log eta


class BinaryTTCNet(nn.Module):
    def __init__(self, config: ModelConfig) -> None:
        super().__init__()
        self.config = config
        c = config
        self.features = FeatExtractNet(
            stem_channels=c.stem_channels,
            out_channels=c.feat_channels,
            res_blocks=c.feat_res_blocks,
            pool_sizes=c.spp_pool_sizes,
            spp_channels=c.spp_channels,
            norm=c.norm,
            extra_blocks=c.feat_extra_blocks,
        )
        self.segnet = SegNet2D(
            feat_channels=c.feat_channels,
            enc_channels=c.enc_channels,
            dec_channels=c.dec_channels,
            full_res_skip=c.full_res_skip,
            norm=c.norm,
            global_context=c.global_context,
            extra_blocks=c.dec_extra_blocks,
            corr_channels=len(CORR_OFFSETS) * c.corr_groups,
            shift_channels=len(CORR_OFFSETS) * c.corr_groups if c.corr_shift_px else 0,
            column_channels=len(CORR_OFFSETS) * c.corr_groups if c.corr_column else 0,
            column_input=c.column_input,
        )
        self.refine = SegRefineNet(
            guide_channels=c.guide_channels,
            channels=c.refine_channels,
            layers=c.refine_layers,
            extra_blocks=c.refine_extra_blocks,
        )
        self.cont_refine = ContRefineNet(
            channels=c.cont_channels,
            dilations=c.cont_dilations,
            norm=c.norm,
            levels=c.cont_levels if c.cont_refine_levels else 0,
        )

    # -- per frame ------------------------------------------------------------------
    def extract(self, images: torch.Tensor) -> torch.Tensor:
        """(B, 3, H, W) -> (B, C, H/3, W/3)."""
        h, w = images.shape[-2:]
        if h % FEATURE_STRIDE or w % FEATURE_STRIDE:
            raise ValueError(f"image size {h}x{w} px: height and width must be multiples of 3")
        return self.features(images)

    def prepare_reference(self, feat_ref: torch.Tensor, image_ref: torch.Tensor) -> ReferenceContext:
        h, w = feat_ref.shape[-2:]
        grid = PaddedGrid.for_features(h, w, self.config.pad_factor, self.config.down_factor)
        terms = self.segnet.prepare(grid.pad(feat_ref), grid)
        return ReferenceContext(image=image_ref, grid=grid, terms=terms, guide=self.refine.guide(image_ref))

    # -- per hypothesis ---------------------------------------------------------------
    def _coarse(self, ctx: ReferenceContext, inputs: SegNetInputs, heads: slice) -> torch.Tensor:
        """SegNet's inputs for B*K hypotheses -> logits of ``heads`` (B*K, n, H, W) at
        input resolution."""
        logits = self.segnet(ctx.terms, inputs, ctx.grid)[:, heads]
        return F.interpolate(logits, size=ctx.image.shape[-2:], mode="bilinear", align_corners=False)

    def scale_inputs(
        self, feat_ref: torch.Tensor, src: torch.Tensor, eta: torch.Tensor, grid: PaddedGrid
    ) -> SegNetInputs:
        """SegNet's inputs for the scale hypotheses eta (B, K): ``src`` warped about the
        image centre, the config's correlation volume (``scale_correlation``) and ``src``
        warped by columns (``column_warp``), each None where the config has none.
        ``feat_ref``: the unpadded reference features (None without a volume)."""
        c = self.config
        warped = scale_warp(src, eta, grid)
        column_warped = column_warp(src, eta, grid) if c.column_input else None
        corr = None
        if c.corr_groups:
            corr = scale_correlation(
                feat_ref,
                src,
                eta,
                warped,
                grid,
                c.corr_groups,
                c.corr_log_step,
                c.corr_shift_px,
                c.corr_column,
                column_warped,
            )
        return SegNetInputs(warped=warped, corr=corr, column_warped=column_warped)

    def classify_eta(self, ctx: ReferenceContext, feat_src: torch.Tensor, eta: torch.Tensor) -> torch.Tensor:
        """eta thresholds (B, K) -> refined logits of p(eta <= eta_i), (B, K, H, W).
        ``feat_src``: the earlier frame's features (B, C, h, w), or one earlier frame per
        threshold (B*K, C, h, w, batch-major: each threshold read on its own pair).

        In eval mode on a CPU the hypotheses go through SegNet ``CPU_INFERENCE_HYPOTHESES``
        at a time (exact: eval-mode batch norm treats samples independently); in training
        mode all at once, so batch norm sees the whole batch."""
        b, k = eta.shape
        if k == 0:
            raise ValueError("classify_eta: no eta thresholds")
        chunk = CPU_INFERENCE_HYPOTHESES if not self.training and eta.device.type == "cpu" else k
        refined = []
        per_threshold = k > 1 and feat_src.shape[0] == b * k
        for start in range(0, k, chunk):
            part = eta[:, start : start + chunk]
            src = feat_src
            if per_threshold:
                src = feat_src.unflatten(0, (b, k))[:, start : start + chunk].flatten(0, 1)
            inputs = self.scale_inputs(ctx.terms.feat, src, part, ctx.grid)
            coarse = self._coarse(ctx, inputs, slice(HEAD_TTC, HEAD_TTC + 1))
            coarse = coarse.view(b, part.shape[1], *coarse.shape[-2:])
            # the full-resolution refiner runs one threshold at a time: on a CPU a batch of
            # full-size maps falls out of cache and costs ~2x more per map (96x288, 2 cores)
            refined += [self.refine(ctx.guide, coarse[:, i : i + 1]) for i in range(part.shape[1])]
        return torch.cat(refined, dim=1)

    def classify_shift(self, ctx: ReferenceContext, feat_src: torch.Tensor, shift_px: torch.Tensor) -> torch.Tensor:
        """shifts (B, K, 2) [input px] -> logits of p(u > u_i), p(v > v_i), (B, K, 2, H, W)."""
        b, k, _ = shift_px.shape
        warped = shift_warp(feat_src, shift_px / FEATURE_STRIDE, ctx.grid)
        coarse = self._coarse(ctx, SegNetInputs(warped=warped), slice(HEAD_U, HEAD_V + 1))
        return coarse.reshape(b, k, 2, *coarse.shape[-2:])

    def continuous(self, ctx: ReferenceContext, feat_src: torch.Tensor) -> ContinuousOutput:
        """Stack ``cont_levels`` maps on uniform eta bins, AUC, then ContRefineNet."""
        c = self.config
        b = feat_src.shape[0]
        levels = uniform_levels(c.cont_eta_min, c.cont_eta_max, c.cont_levels, device=feat_src.device)
        prob_le = torch.sigmoid(self.classify_eta(ctx, feat_src, levels.expand(b, -1)))
        eta_auc = auc_eta(prob_le, c.cont_eta_min, c.cont_eta_max)
        log_eta = self.cont_refine(torch.log(eta_auc), ctx.image, prob_le)
        return ContinuousOutput(levels=levels, prob_le=prob_le, eta_auc=eta_auc, log_eta=log_eta)

    # -- convenience ----------------------------------------------------------------
    def forward(self, image_prev: torch.Tensor, image_latest: torch.Tensor, eta: torch.Tensor) -> torch.Tensor:
        """One pass without caching: eta (B, K) -> logits of p(eta <= eta_i), (B, K, H, W).
        Both frames go through the extractor as one batch (shared weights)."""
        b = image_prev.shape[0]
        feats = self.extract(torch.cat((image_prev, image_latest), dim=0))
        ctx = self.prepare_reference(feats[b:], image_latest)
        return self.classify_eta(ctx, feats[:b], eta)


def count_parameters(module: nn.Module) -> int:
    return sum(p.numel() for p in module.parameters())
