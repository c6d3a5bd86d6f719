"""Procedural textures, drawn from a numpy Generator so a seed fixes every pixel.

TinyRenderer has no mip-mapping: texture detail finer than a screen pixel turns into
noise that differs between frames. The textures here are therefore smooth noise
(a few octaves, most energy at low frequency) rather than white noise.
"""

from __future__ import annotations

import os
from pathlib import Path

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


# --------------------------------------------------------------------------- bank
TEXTURE_KINDS = ("asphalt", "grass", "concrete", "metal", "bark", "foliage", "facade", "sign", "glass", "tyre", "paint")
VARIANTS = 6  # variants per kind (per palette colour for paint)


class TextureBank:
    """Procedural textures written once as PNG files, picked by (kind, variant).

    A bank is a pure function of its seed, so any process that builds the bank with
    the same seed renders the same pixels. Worlds load from it instead of drawing
    fresh textures, which keeps building a world cheap when many are built in a row.
    """

    def __init__(self, seed: int, directory: Path):
        self.seed = seed
        self.dir = Path(directory)
        self.dir.mkdir(parents=True, exist_ok=True)

    def path(self, kind: str, variant: int, palette_index: int = 0) -> Path:
        if kind not in TEXTURE_KINDS:
            raise ValueError(f"unknown texture kind {kind!r}")
        variant %= VARIANTS
        p = self.dir / f"{kind}_{palette_index}_{variant}.png"
        if not p.exists():
            rng = np.random.default_rng([self.seed, TEXTURE_KINDS.index(kind), palette_index, variant])
            img = _draw(kind, rng, palette_index)
            tmp = p.with_name(f".{p.name}.{os.getpid()}.tmp.png")
            cv2.imwrite(str(tmp), cv2.cvtColor(img, cv2.COLOR_RGB2BGR))
            os.replace(tmp, p)
        return p


def _draw(kind: str, rng: np.random.Generator, palette_index: int) -> np.ndarray:
    from sim.vehicles import PALETTE

    if kind == "asphalt":
        return asphalt(rng)
    if kind == "grass":
        return tinted(rng, (0.3, 0.45, 0.2), 1.0)
    if kind == "concrete":
        return tinted(rng, (0.7, 0.7, 0.68), 0.7)
    if kind == "metal":
        return tinted(rng, (0.55, 0.55, 0.6), 0.3)
    if kind == "bark":
        return tinted(rng, (0.35, 0.25, 0.15), 0.6)
    if kind == "foliage":
        return foliage(rng)
    if kind == "facade":
        return facade(rng)
    if kind == "sign":
        return tinted(rng, tuple(rng.choice([(0.1, 0.35, 0.8), (0.1, 0.5, 0.2), (0.85, 0.75, 0.1)])), 0.4)
    if kind == "glass":
        base = np.asarray(PALETTE[palette_index]) * 0.3 + 0.15
        return tinted(rng, tuple(base), 0.5)
    if kind == "tyre":
        return tinted(rng, (0.08, 0.08, 0.08), 0.5)
    return vehicle_paint(rng, PALETTE[palette_index])
