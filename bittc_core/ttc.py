"""Time-to-contact conventions of the project (one place, used everywhere).

Two frames: previous at t0 and latest at t1 = t0 + dt_s. Motion-in-depth
eta = Z(t1) / Z(t0) of the same 3D point. TTC is measured from the latest frame:

    tau_s = dt_s * eta / (1 - eta)      eta = tau_s / (tau_s + dt_s)

approaching: 0 < eta < 1, tau > 0; receding: eta > 1, tau < 0; eta = 1: tau = +inf.
A geofence of threshold tau_i > 0 is the set 0 < tau <= tau_i, i.e. eta <= eta_i.
"""

from __future__ import annotations

import math
import sys

import numpy as np


def _is_tensor(x) -> bool:
    """A torch tensor (without importing torch: whoever made one has imported it)."""
    torch = sys.modules.get("torch")
    return torch is not None and isinstance(x, torch.Tensor)


def tau_to_eta(tau_s, dt_s: float):
    """eta = tau / (tau + dt), 1 where tau is +-inf; on floats, numpy arrays and tensors."""
    if _is_tensor(tau_s):
        torch = sys.modules["torch"]
        return torch.where(torch.isinf(tau_s), torch.ones_like(tau_s), tau_s / (tau_s + dt_s))
    if isinstance(tau_s, np.ndarray):
        with np.errstate(invalid="ignore"):
            return np.where(np.isinf(tau_s), np.ones_like(tau_s), tau_s / (tau_s + dt_s))
    return 1.0 if math.isinf(tau_s) else tau_s / (tau_s + dt_s)


def eta_to_tau(eta, dt_s: float):
    """tau = dt * eta / (1 - eta), +inf where eta == 1 (tensor, or anything numpy takes: float64)."""
    if _is_tensor(eta):
        torch = sys.modules["torch"]
        denom = 1.0 - eta
        tau = dt_s * eta / denom
        return torch.where(denom == 0, torch.full_like(eta, float("inf")), tau)
    eta = np.asarray(eta, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        tau = dt_s * eta / (1.0 - eta)
    return np.where(eta == 1.0, np.inf, tau)


def pair_spans_stride(pair_dt_s: float, frame_dt_s: float, frame_stride: int = 1) -> bool:
    """Whether a pair ``pair_dt_s`` [s] apart spans ``frame_stride`` frame intervals of
    ``frame_dt_s`` [s]: such a pair is read at the network's interval, time compressed
    ``frame_stride`` x (eta is the pair's; a fence tau_i asks for tau_i / frame_stride)."""
    return abs(pair_dt_s - frame_stride * frame_dt_s) <= 1e-6 * frame_stride
