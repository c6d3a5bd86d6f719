"""``bittc``: the Binary-TTC network behind the estimator interface, on torch.

Streaming cache and flip averaging: ``bittc_core.estimator.streaming``. All thresholds
of a call share the same features and are classified together (in batches of
``CPU_INFERENCE_HYPOTHESES`` on a CPU, see ``bittc_core.model.network``). The
onnxruntime backend (``bittc_core.estimator.onnx``) runs the same network exported.

Memory format: on a CPU the network and its inputs are channels-last (NHWC), so that the
oneDNN convolutions need no layout change around each call: a 96x288 job at K = 4 costs
about a fifth less than in the default NCHW layout (2 threads), with logits within 1e-5
of it. Outputs come back contiguous (NCHW).
"""

from __future__ import annotations

import os

import torch

from bittc_core.checkpoint import DEFAULT_WEIGHTS, build_network, load_checkpoint, pick_device
from bittc_core.estimator.streaming import CACHED_FRAMES, TTA_MODES, StreamingNetEstimator, check_tta
from bittc_core.model import BinaryTTCNet, ReferenceContext

__all__ = ["BittcEstimator", "CACHED_FRAMES", "TTA_MODES", "check_tta"]


class BittcEstimator(StreamingNetEstimator):
    name = "bittc"
    backend = "torch"
    sources_per_threshold = True

    def __init__(self, net: BinaryTTCNet, *, device: torch.device | None = None, tta: str = "none") -> None:
        cfg = net.config
        device = device or next(net.parameters()).device
        super().__init__(dt_s=cfg.frame_dt_s, tau_range_s=(cfg.tau_min_s, cfg.tau_max_s), device=device, tta=tta)
        self.net = net.to(self.device).eval()
        self._layout = torch.channels_last if self.device.type == "cpu" else torch.contiguous_format
        self.net.to(memory_format=self._layout)

    @classmethod
    def from_checkpoint(
        cls, path: str | os.PathLike | None = None, device: str = "auto", tta: str = "none"
    ) -> BittcEstimator:
        """Load ``path`` (default: the shipped ``bittc_core/weights/bittc_default.pt``)."""
        check_tta(tta)
        dev = pick_device(device)
        ckpt = load_checkpoint(path or DEFAULT_WEIGHTS, map_location=dev)
        return cls(build_network(ckpt).to(dev), device=dev, tta=tta)

    def _extract(self, views: torch.Tensor) -> torch.Tensor:
        return self.net.extract(views.contiguous(memory_format=self._layout))

    def _make_reference(self, feats: torch.Tensor, views: torch.Tensor) -> ReferenceContext:
        return self.net.prepare_reference(feats, views.contiguous(memory_format=self._layout))

    def _classify(self, ctx: ReferenceContext, feat_prev: torch.Tensor, eta: torch.Tensor) -> torch.Tensor:
        return self.net.classify_eta(ctx, feat_prev, eta).contiguous()

    def _log_eta(self, ctx: ReferenceContext, feat_prev: torch.Tensor) -> torch.Tensor:
        return self.net.continuous(ctx, feat_prev).log_eta.contiguous()
