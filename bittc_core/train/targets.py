"""Hypotheses and their labels for one batch.

TTC: eta thresholds uniform in [tau_to_eta(train_tau_min_s), train_eta_max] or, for a
share of them (``TrainConfig.pixel_threshold_share``), at the eta of a random valid pixel
of the pair in that range plus a uniform jitter of +-``PIXEL_THRESHOLD_JITTER`` (the
geofence's edge then runs through the image, where the eta has to be read precisely), and
for another share (``TrainConfig.inpath_threshold_share``) at the eta of a random in-path
vehicle pixel plus +-``INPATH_THRESHOLD_JITTER`` (the edge then runs through the vehicle a
braking controller reads: whether the fence holds it from frame to frame); label
1[0 < eta <= eta_i] (inside the geofence; thresholds above 1 label every approaching
and static pixel inside and only faster-receding ones outside).
Flow: shifts that are multiples of 3 px (one feature pixel) uniform in
[-max_shift_px, max_shift_px] per axis; labels 1[u > u_i], 1[v > v_i].
Masks: ``valid`` and finite ground truth only.
"""

from __future__ import annotations

import torch

from bittc_core.model.network import FEATURE_STRIDE
from bittc_core.ttc import tau_to_eta


def sample_eta(b: int, k: int, tau_min_s: float, eta_max: float, dt_s: float, gen: torch.Generator) -> torch.Tensor:
    lo = tau_to_eta(tau_min_s, dt_s)
    return lo + (eta_max - lo) * torch.rand(b, k, generator=gen)


PIXEL_THRESHOLD_JITTER = 0.02  # [eta] half-width of the jitter of pixel-drawn thresholds
# [eta] the same for thresholds drawn at in-path vehicle pixels: at 10 Hz, eta 0.96 +- 0.005
# is tau 2.4 s within about 2.1-2.8 s
INPATH_THRESHOLD_JITTER = 0.005


def sample_eta_at_pixels(
    eta: torch.Tensor,
    mask: torch.Tensor,
    k: int,
    tau_min_s: float,
    eta_max: float,
    dt_s: float,
    gen: torch.Generator,
    jitter_eta: float = PIXEL_THRESHOLD_JITTER,
) -> torch.Tensor:
    """eta, mask (B, H, W) -> (B, k) thresholds at the eta of random pixels in ``mask`` of
    each pair in [tau_to_eta(tau_min_s), eta_max], jittered uniformly by +-``jitter_eta``,
    clipped to that range; uniform for a pair with no such pixel. On the CPU (``gen`` is a
    CPU generator)."""
    lo = tau_to_eta(tau_min_s, dt_s)
    eta, mask = eta.detach().cpu(), mask.cpu()
    out = sample_eta(eta.shape[0], k, tau_min_s, eta_max, dt_s, gen)
    jitter = jitter_eta * (2 * torch.rand(eta.shape[0], k, generator=gen) - 1)
    for i in range(eta.shape[0]):
        values = eta[i][mask[i] & (eta[i] >= lo) & (eta[i] <= eta_max)]
        if values.numel():
            pick = torch.randint(values.numel(), (k,), generator=gen)
            out[i] = (values[pick] + jitter[i]).clamp(lo, eta_max)
    return out


def sample_shifts_px(b: int, k: int, max_shift_px: float, gen: torch.Generator) -> torch.Tensor:
    n = int(max_shift_px // FEATURE_STRIDE)
    return FEATURE_STRIDE * torch.randint(-n, n + 1, (b, k, 2), generator=gen).float()


def eta_labels(eta: torch.Tensor, thresholds: torch.Tensor) -> torch.Tensor:
    """eta (B, H, W), thresholds (B, K) -> float (B, K, H, W)."""
    e = eta[:, None]
    return ((e > 0) & (e <= thresholds[:, :, None, None])).float()


def near_outside(eta: torch.Tensor, thresholds: torch.Tensor) -> torch.Tensor:
    """eta (B, H, W), eta thresholds (B, K) -> bool (B, K, H, W): pixels outside each fence
    whose TTC is at most twice its threshold. With eta = tau / (tau + dt) (approaching),
    the threshold eta_k = tau_k / (tau_k + dt) and 2 tau_k gives 2 eta_k / (1 + eta_k),
    whatever the frame interval dt. Static and receding pixels (eta >= 1), and thresholds
    at eta >= 1, get no band."""
    e, t = eta[:, None], thresholds[:, :, None, None]
    return (e > t) & (e <= 2 * t / (1 + t))


def shift_labels(flow_px: torch.Tensor, shifts_px: torch.Tensor) -> torch.Tensor:
    """flow (B, 2, H, W), shifts (B, K, 2) -> float (B, K, 2, H, W) of 1[flow > shift]."""
    return (flow_px[:, None] > shifts_px[..., None, None]).float()


def valid_mask(sample: dict) -> torch.Tensor:
    """(B, H, W) bool: valid pixels with finite eta and flow."""
    return sample["valid"] & torch.isfinite(sample["eta"]) & torch.isfinite(sample["flow_px"]).all(dim=1)
