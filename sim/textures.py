"""Procedural textures, drawn from a numpy Generator so a seed fixes every pixel.

TinyRenderer has no mip-mapping: texture detail finer than a screen pixel turns into
noise that differs between frames. The textures here are therefore smooth noise
(a few octaves, most energy at low frequency) rather than white noise.
"""

from __future__ import annotations

import cv2
import numpy as np

TEXTURE_SIZE_PX = 128


def smooth_noise(rng: np.random.Generator, size_px: int = TEXTURE_SIZE_PX, octaves: int = 5) -> np.ndarray:
    """(size, size) float32 noise in [0, 1], octaves of cubic-upsampled random grids."""
    out = np.zeros((size_px, size_px), np.float32)
    total = 0.0
    for k in range(octaves):
        cells = 2 ** (k + 2)
        amp = 0.7**k
        grid = rng.random((cells, cells), dtype=np.float32)
        out += amp * cv2.resize(grid, (size_px, size_px), interpolation=cv2.INTER_CUBIC)
        total += amp
    out /= total
    lo, hi = float(out.min()), float(out.max())
    return (out - lo) / max(hi - lo, 1e-6)


def tinted(rng: np.random.Generator, rgb: tuple[float, float, float], contrast: float) -> np.ndarray:
    """(size, size, 3) uint8 texture: a base colour modulated by smooth noise."""
    n = smooth_noise(rng)[..., None]
    base = np.asarray(rgb, np.float32)[None, None, :]
    img = base * (1.0 - contrast / 2 + contrast * n)
    return np.clip(img * 255.0, 0, 255).astype(np.uint8)


def asphalt(rng: np.random.Generator) -> np.ndarray:
    grey = rng.uniform(0.25, 0.45)
    return tinted(rng, (grey, grey, grey * 1.02), contrast=1.1)


def vehicle_paint(rng: np.random.Generator, rgb: tuple[float, float, float]) -> np.ndarray:
    """Paint with panel shading, plus a dark band (windows/bumper) so faces have structure."""
    img = tinted(rng, rgb, contrast=0.7).astype(np.float32)
    s = TEXTURE_SIZE_PX
    band = slice(int(s * rng.uniform(0.15, 0.3)), int(s * rng.uniform(0.4, 0.5)))
    img[band] *= 0.35
    img[int(s * 0.85) :] *= 0.5
    lamp = int(s * 0.12)  # tail/head lamps near both side edges
    for x0 in (int(s * 0.04), s - int(s * 0.04) - lamp):
        img[int(s * 0.55) : int(s * 0.55) + lamp // 2, x0 : x0 + lamp] = (200, 30, 20)
    return np.clip(img, 0, 255).astype(np.uint8)


def facade(rng: np.random.Generator) -> np.ndarray:
    """Building facade: wall colour with a grid of darker windows."""
    wall = tuple(rng.uniform(0.35, 0.85, 3))
    img = tinted(rng, wall, contrast=0.3).astype(np.float32)
    s = TEXTURE_SIZE_PX
    n = int(rng.integers(3, 6))
    step = s // n
    for i in range(n):
        for j in range(n):
            y0, x0 = i * step + step // 4, j * step + step // 4
            img[y0 : y0 + step // 2, x0 : x0 + step // 2] *= rng.uniform(0.2, 0.5)
    return np.clip(img, 0, 255).astype(np.uint8)


def foliage(rng: np.random.Generator) -> np.ndarray:
    green = (rng.uniform(0.1, 0.3), rng.uniform(0.35, 0.6), rng.uniform(0.1, 0.25))
    return tinted(rng, green, contrast=0.8)


def sky_gradient(height_px: int, width_px: int, horizon_row: float) -> np.ndarray:
    """(H, W, 3) uint8 sky: pale at the horizon, deeper blue towards the top."""
    rows = np.arange(height_px, dtype=np.float32)[:, None]
    t = np.clip((horizon_row - rows) / max(horizon_row, 1.0), 0.0, 1.0)
    top = np.array([70, 130, 200], np.float32)
    bottom = np.array([200, 220, 235], np.float32)
    col = bottom[None, :] * (1 - t) + top[None, :] * t
    return np.broadcast_to(col[:, None, :], (height_px, width_px, 3)).astype(np.uint8)
