"""Synthetic FlyingChairs-like pairs with exact motion-in-depth and flow.

Each sample is a stack of fronto-parallel textured layers: a full background plane
(instance 0) and 2-6 patches (ellipses or rotated rectangles, instances 1..N, drawn
far to near). Layer k moves as a similarity about its own centre c_k:

    x_latest = c_k + s_k (x_prev - c_k) + t_k      (pixel coordinates, x right, y down)

A fronto-parallel plane whose image magnifies by s_k has eta = Z(t1)/Z(t0) = 1/s_k
exactly, and the flow in the latest grid is (u, v) = x_latest - x_prev, with
x_prev = c_k + (x_latest - t_k - c_k) / s_k. The previous frame samples each layer's
texture at x, the latest frame at x_prev(x), so both frames and the ground truth
agree to float precision. Every pixel has exact ground truth (``valid`` all True).

The sample dict matches ``TTCDataset`` (see the project conventions): image_prev,
image_latest (3, H, W) float32 in [0, 1]; eta, tau_s (H, W); flow_px (2, H, W);
valid (H, W) bool; instance (H, W) int64; dt_s scalar; intrinsics (4,) fx, fy, cx, cy.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
import torch
from torch.utils.data import Dataset

from bittc_core.ttc import eta_to_tau

MARGIN_PX = 48  # texture canvas extends this far beyond the frame on every side


@dataclass(frozen=True)
class SyntheticConfig:
    height_px: int = 96
    width_px: int = 288
    dt_s: float = 0.1  # [s] frame interval
    patches: tuple[int, int] = (2, 6)  # min, max number of patches
    patch_half_size_px: tuple[float, float] = (8.0, 40.0)
    patch_eta: tuple[float, float] = (0.6, 1.15)  # eta of patches, uniform
    background_eta: tuple[float, float] = (0.85, 1.05)
    max_translation_px: float = 12.0  # per axis, uniform in [-max, max]
    noise_std: float = 0.01  # per-frame pixel noise (of a [0, 1] range)
    focal_px: float = 250.0  # nominal intrinsics written to the sample


def smooth_texture(rng: np.random.Generator, h: int, w: int) -> np.ndarray:
    """(h, w, 3) float32 in [0, 1]: octaves of bicubically upsampled noise, tinted."""
    tex = np.zeros((h, w, 3), np.float32)
    for cell, weight in ((2, 0.5), (4, 0.8), (8, 1.0), (16, 0.8), (32, 0.5)):
        small = rng.standard_normal((h // cell + 2, w // cell + 2, 3)).astype(np.float32)
        tex += weight * cv2.resize(small, (w, h), interpolation=cv2.INTER_CUBIC)
    tex = tex * rng.uniform(0.5, 1.5, 3).astype(np.float32)
    tex -= tex.min()
    return (tex / max(float(tex.max()), 1e-6)).astype(np.float32)


@dataclass
class _Layer:
    texture: np.ndarray  # canvas in previous-frame coordinates shifted by MARGIN_PX
    centre: np.ndarray  # (2,) c_k [px]
    scale: float  # s_k = 1 / eta
    shift: np.ndarray  # (2,) t_k [px]
    shape: str  # "plane", "ellipse", "rect"
    pos: np.ndarray  # (2,) patch centre in the previous frame [px]
    half: np.ndarray  # (2,) half sizes [px]
    angle: float  # [rad]

    def mask(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Coverage at previous-frame coordinates (x, y)."""
        if self.shape == "plane":
            return np.ones(x.shape, bool)
        ca, sa = np.cos(self.angle), np.sin(self.angle)
        dx, dy = x - self.pos[0], y - self.pos[1]
        a = (ca * dx + sa * dy) / self.half[0]
        b = (-sa * dx + ca * dy) / self.half[1]
        if self.shape == "ellipse":
            return a * a + b * b <= 1.0
        return (np.abs(a) <= 1.0) & (np.abs(b) <= 1.0)

    def sample(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return cv2.remap(
            self.texture,
            (x + MARGIN_PX).astype(np.float32),
            (y + MARGIN_PX).astype(np.float32),
            cv2.INTER_LINEAR,
            borderMode=cv2.BORDER_REFLECT_101,
        )

    def to_prev(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """x_prev = c + (x_latest - t - c) / s."""
        return (
            self.centre[0] + (x - self.shift[0] - self.centre[0]) / self.scale,
            self.centre[1] + (y - self.shift[1] - self.centre[1]) / self.scale,
        )


class SyntheticPairs(Dataset):
    """``length`` pairs; sample i is a pure function of (seed, i)."""

    def __init__(self, length: int, config: SyntheticConfig = SyntheticConfig(), seed: int = 0) -> None:
        if length <= 0:
            raise ValueError(f"SyntheticPairs length={length}: must be > 0")
        self.length = length
        self.config = config
        self.seed = seed

    def __len__(self) -> int:
        return self.length

    def _layers(self, rng: np.random.Generator) -> list[_Layer]:
        c = self.config
        h, w = c.height_px, c.width_px
        canvas = (h + 2 * MARGIN_PX, w + 2 * MARGIN_PX)
        t = lambda: rng.uniform(-c.max_translation_px, c.max_translation_px, 2)  # noqa: E731
        layers = [
            _Layer(
                texture=smooth_texture(rng, *canvas),
                centre=np.array([rng.uniform(0.3, 0.7) * w, rng.uniform(0.3, 0.7) * h]),
                scale=1.0 / rng.uniform(*c.background_eta),
                shift=0.3 * t(),
                shape="plane",
                pos=np.zeros(2),
                half=np.ones(2),
                angle=0.0,
            )
        ]
        for _ in range(rng.integers(c.patches[0], c.patches[1] + 1)):
            pos = np.array([rng.uniform(0, w), rng.uniform(0, h)])
            half = rng.uniform(*c.patch_half_size_px, 2)
            layers.append(
                _Layer(
                    texture=smooth_texture(rng, *canvas),
                    centre=pos + rng.uniform(-0.5, 0.5, 2) * half,
                    scale=1.0 / rng.uniform(*c.patch_eta),
                    shift=t(),
                    shape=str(rng.choice(["ellipse", "rect"])),
                    pos=pos,
                    half=half,
                    angle=float(rng.uniform(0, np.pi)),
                )
            )
        return layers

    def __getitem__(self, index: int) -> dict[str, torch.Tensor]:
        if not 0 <= index < self.length:
            raise IndexError(index)
        c = self.config
        rng = np.random.default_rng([self.seed, index])
        h, w = c.height_px, c.width_px
        ys, xs = np.mgrid[0:h, 0:w].astype(np.float64)
        prev = np.zeros((h, w, 3), np.float32)
        latest = np.zeros((h, w, 3), np.float32)
        eta = np.ones((h, w), np.float32)
        flow = np.zeros((h, w, 2), np.float32)
        instance = np.zeros((h, w), np.int64)
        for k, layer in enumerate(self._layers(rng)):
            m_prev = layer.mask(xs, ys)
            prev[m_prev] = layer.sample(xs, ys)[m_prev]
            xp, yp = layer.to_prev(xs, ys)
            m = layer.mask(xp, yp)
            latest[m] = layer.sample(xp, yp)[m]
            eta[m] = 1.0 / layer.scale
            flow[m, 0] = (xs - xp)[m]
            flow[m, 1] = (ys - yp)[m]
            instance[m] = k
        for img in (prev, latest):
            img += rng.normal(0.0, c.noise_std, img.shape).astype(np.float32)
        to_chw = lambda a: torch.from_numpy(np.clip(a, 0.0, 1.0).transpose(2, 0, 1).copy())  # noqa: E731
        return {
            "image_prev": to_chw(prev),
            "image_latest": to_chw(latest),
            "eta": torch.from_numpy(eta),
            "tau_s": torch.from_numpy(eta_to_tau(eta, c.dt_s).astype(np.float32)),
            "flow_px": torch.from_numpy(flow.transpose(2, 0, 1).copy()),
            "valid": torch.ones((h, w), dtype=torch.bool),
            "instance": torch.from_numpy(instance),
            "dt_s": torch.tensor(c.dt_s, dtype=torch.float32),
            "intrinsics": torch.tensor([c.focal_px, c.focal_px, (w - 1) / 2, (h - 1) / 2], dtype=torch.float32),
        }
