"""``oracle``: exact maps from a sample's ground-truth eta (evaluation only).

Call ``set_ground_truth(eta)`` with the (H, W) motion-in-depth of the pair before each
``geofence`` / ``quantized`` / ``continuous`` call; the images are only checked for size.
Pixels with non-finite or non-positive eta (no ground truth) are outside every geofence.

``oracle-auc`` (``auc_volume=(eta_lo, eta_hi, levels)``): the same exact geofences, but
the continuous output is the AUC (paper Eq. 12, ``bittc_core.model.auc``) of the exact
maps at the network's continuous levels, so its MiD is what the quantization of that
volume alone costs, the floor of the network's AUC before its refinement.
"""

from __future__ import annotations

import numpy as np
import torch

from bittc_core.estimator.base import Estimator, EstimatorInputError
from bittc_core.model.auc import auc_eta, uniform_levels


class OracleEstimator(Estimator):
    name = "oracle"

    def __init__(self, dt_s: float = 0.1, auc_volume: tuple[float, float, int] | None = None) -> None:
        super().__init__(dt_s=dt_s, tau_range_s=(1e-3, 1e6))
        self._eta: np.ndarray | None = None
        self.auc_volume = auc_volume
        if auc_volume is not None:
            lo, hi, levels = auc_volume
            if not (0 < lo < hi and int(levels) == levels >= 2):
                raise EstimatorInputError(
                    f"oracle auc_volume={auc_volume}: expected (eta_lo, eta_hi, levels) "
                    "with 0 < eta_lo < eta_hi and levels >= 2"
                )
            self.name = "oracle-auc"

    def set_ground_truth(self, eta) -> None:
        """eta: (H, W) tensor or array, Z(t1)/Z(t0) in the latest grid."""
        if isinstance(eta, torch.Tensor):
            eta = eta.detach().cpu().numpy()
        eta = np.asarray(eta, dtype=np.float32)
        if eta.ndim != 2:
            raise EstimatorInputError(f"oracle ground truth: expected (H, W) eta, got shape {eta.shape}")
        self._eta = eta

    def _truth(self, latest: torch.Tensor) -> np.ndarray:
        if self._eta is None:
            raise EstimatorInputError("oracle: call set_ground_truth(eta) before asking for maps")
        if self._eta.shape != tuple(latest.shape[-2:]):
            raise EstimatorInputError(
                f"oracle: ground truth {self._eta.shape} does not match the images {tuple(latest.shape[-2:])}"
            )
        return self._eta

    def _geofence(self, prev: torch.Tensor, latest: torch.Tensor, eta: np.ndarray) -> np.ndarray:
        truth = self._truth(latest)
        with np.errstate(invalid="ignore"):
            inside = (truth[None] <= eta.astype(np.float32)[:, None, None]) & (truth[None] > 0)
        return inside.astype(np.float32)

    def _motion_in_depth(self, prev: torch.Tensor, latest: torch.Tensor) -> np.ndarray:
        if self.auc_volume is None:
            return self._truth(latest).copy()
        lo, hi, levels = self.auc_volume
        prob_le = self._geofence(prev, latest, uniform_levels(lo, hi, int(levels)).numpy())
        return auc_eta(torch.from_numpy(prob_le), lo, hi, dim=0)[0].numpy()
