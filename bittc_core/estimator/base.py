"""The estimator interface shared by the network, the flow baseline and the oracle.

Convention: ``image_prev`` at t0, ``image_latest`` at t1 = t0 + dt_s; every output map is
(H, W) or (K, H, W) in the latest frame's pixel grid, returned as numpy float32 on the
CPU. A geofence of threshold tau_i [s] is p(0 < tau <= tau_i) = p(eta <= eta_i),
eta_i = tau_i / (tau_i + dt_s) (see ``bittc_core.ttc``).

Images: numpy uint8 (H, W, 3) RGB, or float tensors (3, H, W) / (1, 3, H, W) in [0, 1].
Bad input raises ``EstimatorInputError`` (a ValueError) naming the bad value.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np
import torch

from bittc_core.errors import ConfigError
from bittc_core.ttc import eta_to_tau, tau_to_eta

RANGE_RTOL = 1e-6  # thresholds computed in float round-trips may graze the range ends


class EstimatorInputError(ConfigError):
    """An image or threshold list the estimator cannot use; the message names it."""


def as_image_tensor(image, name: str) -> torch.Tensor:
    """-> float32 (1, 3, H, W) in [0, 1] on the CPU (no copy for a float32 CPU tensor)."""
    if isinstance(image, np.ndarray):
        if image.dtype != np.uint8:
            raise EstimatorInputError(f"{name}: numpy images must be uint8 HxWx3, got dtype {image.dtype}")
        if image.ndim != 3 or image.shape[2] != 3:
            raise EstimatorInputError(f"{name}: expected shape (H, W, 3), got {image.shape}")
        return torch.from_numpy(np.ascontiguousarray(image)).permute(2, 0, 1)[None].float() / 255.0
    if isinstance(image, torch.Tensor):
        if not image.is_floating_point():
            raise EstimatorInputError(f"{name}: tensors must be float in [0, 1], got dtype {image.dtype}")
        shape = tuple(image.shape)
        if image.ndim == 3:
            image = image[None]
        if image.ndim != 4 or image.shape[0] != 1 or image.shape[1] != 3:
            raise EstimatorInputError(f"{name}: expected a (3, H, W) or (1, 3, H, W) tensor, got shape {shape}")
        image = image.detach().to("cpu", torch.float32)
        if not torch.isfinite(image).all():
            raise EstimatorInputError(f"{name}: contains NaN or inf")
        lo, hi = float(image.min()), float(image.max())
        if lo < 0.0 or hi > 1.0:
            raise EstimatorInputError(f"{name}: values must lie in [0, 1], got [{lo:.3g}, {hi:.3g}]")
        return image
    raise EstimatorInputError(f"{name}: expected a numpy uint8 array or a float tensor, got {type(image).__name__}")


def as_image_pair(image_prev, image_latest) -> tuple[torch.Tensor, torch.Tensor]:
    prev = as_image_tensor(image_prev, "image_prev")
    latest = as_image_tensor(image_latest, "image_latest")
    if prev.shape != latest.shape:
        raise EstimatorInputError(
            f"frames differ in size: image_prev {tuple(prev.shape[-2:])} vs image_latest {tuple(latest.shape[-2:])}"
        )
    return prev, latest


def as_thresholds(thresholds_s, tau_range_s: tuple[float, float], *, sorted_: bool) -> np.ndarray:
    """-> float64 (K,) thresholds [s], validated; ``sorted_`` demands strictly increasing."""
    if isinstance(thresholds_s, torch.Tensor):
        thresholds_s = thresholds_s.detach().cpu().numpy()
    try:
        thr = np.asarray(thresholds_s, dtype=np.float64)
    except (TypeError, ValueError):
        raise EstimatorInputError(f"thresholds_s={thresholds_s!r}: not a list of numbers") from None
    if thr.ndim != 1:
        raise EstimatorInputError(f"thresholds_s: expected a 1-D list, got shape {thr.shape}")
    if thr.size == 0:
        raise EstimatorInputError("thresholds_s is empty: give at least one threshold [s]")
    for t in thr:
        if not np.isfinite(t) or t <= 0.0:
            raise EstimatorInputError(f"threshold {float(t)!r} s: thresholds must be finite and > 0")
        lo, hi = tau_range_s
        if not lo * (1 - RANGE_RTOL) <= t <= hi * (1 + RANGE_RTOL):
            raise EstimatorInputError(f"threshold {t:g} s outside the trained range [{lo:g}, {hi:g}] s")
    if sorted_:
        bad = np.nonzero(np.diff(thr) <= 0)[0]
        if bad.size:
            i = int(bad[0])
            raise EstimatorInputError(
                f"thresholds_s must increase strictly: {thr[i]:g} s is followed by {thr[i + 1]:g} s"
            )
    return thr


def quantize(prob_le: np.ndarray) -> np.ndarray:
    """Paper Eq. 10-11 on geofence maps P_i = p(tau <= tau_i), thresholds increasing.

    (K, H, W) -> int64 (H, W) bin index: 0 for (0, tau_1], i for (tau_i, tau_i+1],
    K for beyond tau_K (or receding). P is first made monotone in i (running max: a CDF
    cannot decrease); the bin probabilities are P_1, P_2 - P_1, ..., 1 - P_K and the
    argmax wins (ties: the nearer bin). Agreement with the binary maps: where every
    P_i is at least 0.25 from 0.5, the jump across 0.5 exceeds all other bins together,
    so the bin is exactly the index of the first map with P_i > 0.5 (K if none).
    """
    mono = np.maximum.accumulate(prob_le, axis=0)
    k = mono.shape[0]
    bins = np.empty((k + 1,) + mono.shape[1:], dtype=np.float32)
    bins[0] = mono[0]
    bins[1:k] = np.diff(mono, axis=0)
    bins[k] = 1.0 - mono[-1]
    return np.argmax(bins, axis=0).astype(np.int64)


class Estimator(ABC):
    """Geofence / quantized / continuous TTC from two frames. Subclasses implement
    ``_geofence(prev, latest, eta_thresholds)`` and ``_motion_in_depth(prev, latest)``
    on validated (1, 3, H, W) float tensors."""

    name: str = ""

    def __init__(self, *, dt_s: float, tau_range_s: tuple[float, float]) -> None:
        self.dt_s = float(dt_s)  # [s] time between the two frames
        self.tau_range_s = tau_range_s  # [s] accepted geofence thresholds

    def geofence(self, image_prev, image_latest, thresholds_s) -> np.ndarray:
        """(K, H, W) float32 p(0 < tau <= tau_i) for each threshold, in the given order."""
        prev, latest = as_image_pair(image_prev, image_latest)
        thr = as_thresholds(thresholds_s, self.tau_range_s, sorted_=False)
        return self._geofence(prev, latest, tau_to_eta(thr, self.dt_s))

    def geofence_pairs(self, images_prev, image_latest, thresholds_s) -> np.ndarray:
        """(K, H, W) float32 p(0 < tau <= tau_i), threshold i read on the pair
        (``images_prev[i]``, ``image_latest``): fences of one frame read on pairs of
        different intervals (each threshold in this estimator's own time base). Here each
        distinct earlier frame (the same object) is read in a call of its own; the network
        reads them all in one."""
        if len(images_prev) != len(thresholds_s):
            raise EstimatorInputError(
                f"geofence_pairs: {len(images_prev)} earlier frames for {len(thresholds_s)} thresholds"
            )
        groups: dict[int, list[int]] = {}
        for i, image in enumerate(images_prev):
            groups.setdefault(id(image), []).append(i)
        out: list[np.ndarray | None] = [None] * len(thresholds_s)
        for idx in groups.values():
            maps = self.geofence(images_prev[idx[0]], image_latest, [thresholds_s[i] for i in idx])
            for m, i in zip(maps, idx):
                out[i] = m
        return np.stack(out)

    def quantized(self, image_prev, image_latest, thresholds_s) -> np.ndarray:
        """(H, W) int64 bin index over strictly increasing thresholds (see ``quantize``)."""
        prev, latest = as_image_pair(image_prev, image_latest)
        thr = as_thresholds(thresholds_s, self.tau_range_s, sorted_=True)
        return quantize(self._geofence(prev, latest, tau_to_eta(thr, self.dt_s)))

    def motion_in_depth(self, image_prev, image_latest) -> np.ndarray:
        """(H, W) float32 eta = Z(t1) / Z(t0)."""
        prev, latest = as_image_pair(image_prev, image_latest)
        return self._motion_in_depth(prev, latest)

    def continuous(self, image_prev, image_latest) -> np.ndarray:
        """(H, W) float32 TTC [s] from the latest frame (+inf where eta == 1, < 0 receding)."""
        return eta_to_tau(self.motion_in_depth(image_prev, image_latest), self.dt_s).astype(np.float32)

    @abstractmethod
    def _geofence(self, prev: torch.Tensor, latest: torch.Tensor, eta: np.ndarray) -> np.ndarray: ...

    @abstractmethod
    def _motion_in_depth(self, prev: torch.Tensor, latest: torch.Tensor) -> np.ndarray: ...
