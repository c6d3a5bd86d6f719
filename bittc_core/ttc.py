"""Time-to-contact conventions of the project (one place, used everywhere).

Two frames: previous at t0 and latest at t1 = t0 + dt_s. Motion-in-depth
eta = Z(t1) / Z(t0) of the same 3D point. TTC is measured from the latest frame:

    tau_s = dt_s * eta / (1 - eta)      eta = tau_s / (tau_s + dt_s)

approaching: 0 < eta < 1, tau > 0; receding: eta > 1, tau < 0; eta = 1: tau = +inf.
A geofence of threshold tau_i > 0 is the set 0 < tau <= tau_i, i.e. eta <= eta_i.
"""

from __future__ import annotations

import numpy as np
import torch


def tau_to_eta(tau_s, dt_s: float):
    """eta_i = tau / (tau + dt); works on floats, numpy arrays and tensors."""
    return tau_s / (tau_s + dt_s)


def eta_to_tau(eta, dt_s: float):
    """tau = dt * eta / (1 - eta), +inf where eta == 1 (tensor or numpy)."""
    if isinstance(eta, torch.Tensor):
        denom = 1.0 - eta
        tau = dt_s * eta / denom
        return torch.where(denom == 0, torch.full_like(eta, float("inf")), tau)
    eta = np.asarray(eta, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        tau = dt_s * eta / (1.0 - eta)
    return np.where(eta == 1.0, np.inf, tau)
