"""The streaming cache shared by the network's backends (torch, onnxruntime).

The features of each frame are computed once. The estimator keeps the last
``CACHED_FRAMES`` frames it saw (the frame's views and their features) and the reference
context of the last latest frame. A frame is recognised by exact pixel equality (one
``torch.equal``, ~0.05 ms at 96x288), not by object identity, so it works whether the
caller passes the same object, a copy, or a fresh numpy array each call: in a stream
(f0, f1), (f1, f2), ... the features of f1 computed as the latest frame are reused when
f1 comes back as ``image_prev``; calling ``geofence`` and then ``continuous`` on the same
pair recomputes nothing but the hypotheses.

Flip averaging (``tta="flip"``, a test-time self-ensemble): each frame also goes through
the network mirrored left to right (the mirrored pair is a valid scene with the same
eta and TTC, and the network was trained on mirrored pairs); the mirrored view's
outputs are mirrored back and averaged with the plain view's, geofence logits and log
eta alike. The two views ride along the batch dimension (view 0 plain, view 1
mirrored), so the cache holds both views' features and the cost is about 2x.

A backend implements four steps on the views (V, 3, H, W) (float32 CPU tensors for the
onnxruntime backend, on the model's device for torch): ``_extract``, ``_make_reference``,
``_classify`` (eta (V, K) -> logits (V, K, H, W)) and ``_log_eta`` (-> (V, 1, H, W)).
"""

from __future__ import annotations

import copy
from abc import abstractmethod
from collections import OrderedDict
from typing import Any

import numpy as np
import torch

from bittc_core.estimator.base import Estimator, EstimatorInputError, as_image_pair, as_thresholds
from bittc_core.model.flip import flip_views, merge_flip_views
from bittc_core.ttc import tau_to_eta

#: frames whose features the cache holds: the least recently used is evicted, so a stream of
#: pairs (k - n, k) for every k (four frames touched between two uses of frame k - n at n = 3)
#: reuses every frame's features for n <= (CACHED_FRAMES + 1) / 2 = 3, the controller's
#: default stride; a larger stride extracts the older frame again (and is charged for it).
#: With the fovea's shorter pair read after it, (k - 1, k), still one new frame a job
CACHED_FRAMES = 5
TTA_MODES = ("none", "flip")


def check_tta(tta: str) -> None:
    if tta not in TTA_MODES:
        raise EstimatorInputError(f"tta={tta!r}: expected one of {TTA_MODES}")


class StreamingNetEstimator(Estimator):
    """The network behind the estimator interface, with the streaming cache."""

    cached_frames = CACHED_FRAMES  # frames whose features the cache holds
    # the backend classifies each threshold on an earlier frame of its own in one call
    # (``geofence_pairs``); otherwise one call per earlier frame
    sources_per_threshold = False

    def __init__(
        self, *, dt_s: float, tau_range_s: tuple[float, float], device: torch.device, tta: str = "none"
    ) -> None:
        check_tta(tta)
        super().__init__(dt_s=dt_s, tau_range_s=tau_range_s)
        self.device = device
        self._tta = tta
        self._features: OrderedDict[int, tuple[torch.Tensor, Any]] = OrderedDict()
        self._next_key = 0
        self._reference: tuple[torch.Tensor, Any] | None = None
        self.feature_computations = 0  # frames that went through the extractor (for tests)

    @property
    def tta(self) -> str:
        """Test-time averaging, fixed at construction (the cache holds its views)."""
        return self._tta

    def reset(self) -> None:
        """Forget cached frames (e.g. at the start of a new episode)."""
        self._features.clear()
        self._reference = None

    def fork(self, tta: str | None = None) -> StreamingNetEstimator:
        """Another estimator on the same model (network or sessions, not copied) with its
        own empty cache, and ``tta`` if given."""
        other = copy.copy(self)
        if tta is not None:
            check_tta(tta)
            other._tta = tta
        other._features, other._reference, other._next_key, other.feature_computations = OrderedDict(), None, 0, 0
        return other

    # -- backend ------------------------------------------------------------------------
    @abstractmethod
    def _extract(self, views: torch.Tensor) -> Any: ...

    @abstractmethod
    def _make_reference(self, feats: Any, views: torch.Tensor) -> Any: ...

    @abstractmethod
    def _classify(self, ctx: Any, feat_prev: Any, eta: torch.Tensor) -> torch.Tensor: ...

    @abstractmethod
    def _log_eta(self, ctx: Any, feat_prev: Any) -> torch.Tensor: ...

    def _check_size(self, image: torch.Tensor) -> None:
        if image.shape[-1] % 3 or image.shape[-2] % 3:
            raise EstimatorInputError(
                f"image size {tuple(image.shape[-2:])} px: height and width must be multiples of 3"
            )

    # -- cache --------------------------------------------------------------------------
    def _views(self, image: torch.Tensor) -> torch.Tensor:
        """(1, ...) -> a new (V, ...) tensor: the plain view, and the mirrored one with
        ``tta="flip"`` (a copy either way: the caller may reuse its buffer)."""
        return flip_views(image) if self.tta == "flip" else image.clone()

    def _merge(self, out: torch.Tensor) -> torch.Tensor:
        """(V, ..., W) outputs in the views' grids (last axis: image x) -> (..., W) in the
        plain grid, averaged."""
        return merge_flip_views(out)[0] if self.tta == "flip" else out[0]

    def _frame_features(self, image: torch.Tensor) -> tuple[torch.Tensor, Any]:
        """(1, 3, H, W) -> (its views on the device (V, 3, H, W), their features), from the
        cache when the pixels match."""
        image = image.to(self.device, non_blocking=True)
        for key, (cached, feats) in self._features.items():
            if cached.shape[1:] == image.shape[1:] and torch.equal(cached[:1], image):
                self._features.move_to_end(key)
                return cached, feats
        # the same object is returned now and from the cache later, so that ``_prepare``
        # recognises a repeated latest frame by identity
        views = self._views(image)
        feats = self._extract(views)
        self.feature_computations += 1
        self._features[self._next_key] = (views, feats)
        self._next_key += 1
        while len(self._features) > CACHED_FRAMES:
            self._features.popitem(last=False)
        return views, feats

    def _prepare(self, prev: torch.Tensor, latest: torch.Tensor) -> tuple[Any, Any]:
        self._check_size(prev)
        # prev first, so that the least recently used entry evicted by a new latest frame
        # is the older frame, never the one just matched
        _, feat_prev = self._frame_features(prev)
        latest, feat_latest = self._frame_features(latest)
        if self._reference is not None and self._reference[0] is latest:
            ctx = self._reference[1]
        else:
            ctx = self._make_reference(feat_latest, latest)
            self._reference = (latest, ctx)
        return ctx, feat_prev

    # -- estimator ----------------------------------------------------------------------
    @torch.inference_mode()
    def _geofence(self, prev: torch.Tensor, latest: torch.Tensor, eta: np.ndarray) -> np.ndarray:
        ctx, feat_prev = self._prepare(prev, latest)
        return self._fence_maps(ctx, feat_prev, eta)

    def _fence_maps(self, ctx: Any, feat_src: Any, eta: np.ndarray) -> np.ndarray:
        """The classified thresholds ``eta`` on the prepared pair(s) -> (K, H, W) probabilities
        in the plain view's grid (the views of the latest frame merged)."""
        views = self._reference[0].shape[0]
        eta_t = torch.as_tensor(eta, dtype=torch.float32, device=self.device)[None].expand(views, -1)
        return torch.sigmoid(self._merge(self._classify(ctx, feat_src, eta_t))).float().cpu().numpy()

    def geofence_pairs(self, images_prev, image_latest, thresholds_s) -> np.ndarray:
        if not self.sources_per_threshold or len(images_prev) != len(thresholds_s):
            return super().geofence_pairs(images_prev, image_latest, thresholds_s)
        converted: dict[int, tuple] = {}  # each distinct earlier frame (the same object) converted once
        for p in images_prev:
            if id(p) not in converted:
                converted[id(p)] = as_image_pair(p, image_latest)
        thr = as_thresholds(thresholds_s, self.tau_range_s, sorted_=False)
        prevs = [converted[id(p)][0] for p in images_prev]
        return self._geofence_pairs(prevs, converted[id(images_prev[0])][1], tau_to_eta(thr, self.dt_s))

    @torch.inference_mode()
    def _geofence_pairs(self, prevs: list[torch.Tensor], latest: torch.Tensor, eta: np.ndarray) -> np.ndarray:
        """Each threshold on its own earlier frame, one classify call: the earlier frames'
        features (from the cache where the pixels match) stacked per threshold."""
        distinct: dict[int, Any] = {}  # each earlier frame prepared once, in the order given
        ctx = None
        for prev in prevs:
            if id(prev) not in distinct:
                ctx, distinct[id(prev)] = self._prepare(prev, latest)  # the reference is made once
        feat_src = torch.stack([distinct[id(prev)] for prev in prevs], dim=1).flatten(0, 1)  # (V*K, C, h, w)
        return self._fence_maps(ctx, feat_src, eta)

    @torch.inference_mode()
    def _motion_in_depth(self, prev: torch.Tensor, latest: torch.Tensor) -> np.ndarray:
        ctx, feat_prev = self._prepare(prev, latest)
        return torch.exp(self._merge(self._log_eta(ctx, feat_prev)[:, 0])).float().cpu().numpy()
