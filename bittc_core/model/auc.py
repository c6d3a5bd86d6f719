"""Continuous motion-in-depth from stacked binary maps: the AUC (paper Eq. 12).

Convention: the K thresholds are bin centres of [eta_lo, eta_hi] cut into K bins of
width d = (eta_hi - eta_lo) / K, eta_i = eta_lo + (i + 1/2) d. With the paper's maps
B_i = p(eta > eta_i) (our network outputs P_i = p(eta <= eta_i) = 1 - B_i),

    eta_hat = eta_lo + d * sum_i B_i,

the midpoint rule for eta_lo + integral of 1[eta > e] de over [eta_lo, eta_hi]. A sharp
step at a bin edge eta_lo + m d gives eta_hat = eta_lo + m d exactly; a step inside a
bin gives that bin's centre; values outside the range clamp to its ends. TTC follows
from eta (``bittc_core.ttc.eta_to_tau``).
"""

from __future__ import annotations

import torch


def uniform_levels(eta_lo: float, eta_hi: float, levels: int, *, device: torch.device | None = None) -> torch.Tensor:
    """(K,) bin centres eta_i = eta_lo + (i + 1/2) d."""
    step = (eta_hi - eta_lo) / levels
    return eta_lo + step * (torch.arange(levels, device=device, dtype=torch.float32) + 0.5)


def auc_eta(prob_le: torch.Tensor, eta_lo: float, eta_hi: float, dim: int = 1) -> torch.Tensor:
    """prob_le (..., K, ...) = p(eta <= eta_i) on uniform bin centres -> eta_hat (K dim kept as 1)."""
    levels = prob_le.shape[dim]
    step = (eta_hi - eta_lo) / levels
    return eta_lo + step * (1.0 - prob_le).sum(dim=dim, keepdim=True)
