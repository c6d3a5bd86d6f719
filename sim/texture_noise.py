"""The noise every procedural texture is made of (``sim.textures``, ``sim.vehicle_textures``):
smooth multi-octave noise, a tint with that noise, and anti-aliased patches. Drawn from a
numpy Generator, so a seed fixes every texel."""

from __future__ import annotations

import cv2
import numpy as np

TEXTURE_SIZE_PX = 128


def smooth_noise(
    rng: np.random.Generator, size_px: int = TEXTURE_SIZE_PX, octaves: int = 5, first_cells: int = 4, decay: float = 0.7
) -> np.ndarray:
    """(size, size) float32 noise in [0, 1], octaves of cubic-upsampled random grids.

    Octave k has ``first_cells * 2**k`` cells per side and amplitude ``decay**k``.
    """
    out = np.zeros((size_px, size_px), np.float32)
    total = 0.0
    for k in range(octaves):
        cells = first_cells * 2**k
        amp = decay**k
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


def patches(rng: np.random.Generator, size_px: int, count: int, radius_px: tuple[float, float]) -> np.ndarray:
    """(size, size) float32 in [-1, 1]: ``count`` filled ellipses of random sign and
    strength, drawn at 4x and area-averaged so their edges are anti-aliased."""
    k = 4
    canvas = np.zeros((size_px * k, size_px * k), np.float32)
    for _ in range(count):
        centre = (int(rng.integers(size_px * k)), int(rng.integers(size_px * k)))
        axes = tuple(int(a * k) for a in rng.uniform(*radius_px, size=2))
        value = float(rng.choice([-1.0, 1.0]) * rng.uniform(0.4, 1.0))
        cv2.ellipse(canvas, centre, axes, float(rng.uniform(0, 180)), 0, 360, value, -1, cv2.LINE_AA)
    return np.clip(cv2.resize(canvas, (size_px, size_px), interpolation=cv2.INTER_AREA), -1.0, 1.0)
