"""Vehicle textures of ``sim.textures.TextureBank``: the plain paint (panel shading, a dark
band, lamps), the detailed style's shading and spots, and the dressed style's framed
windows, number plates and lamp lenses. Each draws from a numpy Generator, so a seed fixes
every texel; sizes are ``TEXTURE_SIZE_PX`` square."""

from __future__ import annotations

import cv2
import numpy as np

from sim.texture_noise import TEXTURE_SIZE_PX, patches, smooth_noise, tinted


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


def vehicle_detail(
    rng: np.random.Generator, img: np.ndarray, noise_contrast: float, spot_contrast: float, spots: int = 30
) -> np.ndarray:
    """A vehicle texture (uint8) with mid-frequency shading (cells of 1/8 to 1/32 of the
    face) and ``spots`` anti-aliased spots 2-8 texels in radius multiplied in."""
    s = img.shape[0]
    n = smooth_noise(rng, s, octaves=3, first_cells=8, decay=0.8) - 0.5
    shade = 1.0 + noise_contrast * n + spot_contrast * patches(rng, s, spots, (2.0, 8.0))
    return np.clip(img.astype(np.float32) * shade[..., None], 0, 255).astype(np.uint8)


def window_frames(rng: np.random.Generator, glass: np.ndarray, palette_index: int) -> np.ndarray:
    """Glass (uint8) set in frames of the body's colour: a border 6-10 % of the face, a
    pillar at 45-60 % across, and a lighter band across the panes (a reflection of the sky).
    Every face of the cabin box shows it (windscreen, side windows, rear window)."""
    from sim.vehicles import PALETTE

    s = glass.shape[0]
    img = glass.astype(np.float32)
    v, u = np.mgrid[0:s, 0:s].astype(np.float32) / s
    slope, offset = rng.uniform(0.4, 1.2), rng.uniform(-0.2, 0.6)
    band = np.exp(-(((v - slope * u - offset) / 0.12) ** 2))  # a soft diagonal reflection
    img *= 1.0 + 0.6 * band[..., None]
    frame = np.asarray(PALETTE[palette_index], np.float32) * 255.0 * rng.uniform(0.75, 0.95)
    border = int(s * rng.uniform(0.06, 0.10))
    pillar = int(s * rng.uniform(0.45, 0.60))
    mask = np.zeros((s, s), bool)
    mask[:border] = mask[-border:] = True
    mask[:, :border] = mask[:, -border:] = True
    mask[:, pillar - border // 2 : pillar + border // 2 + 1] = True
    img[mask] = frame
    return np.clip(img, 0, 255).astype(np.uint8)


def number_plate(rng: np.random.Generator) -> np.ndarray:
    """A plate: white or yellow, a dark border, six to eight dark characters as bars and rings."""
    s = TEXTURE_SIZE_PX
    base = (0.93, 0.93, 0.9) if rng.random() < 0.7 else (0.95, 0.8, 0.1)
    img = tinted(rng, base, 0.1).astype(np.float32)
    ink = np.array([20.0, 20.0, 25.0])
    edge = s // 20
    img[:edge] = img[-edge:] = ink
    img[:, : edge // 2] = img[:, -edge // 2 :] = ink
    n = int(rng.integers(6, 9))
    x0, x1 = 0.12 * s, 0.95 * s
    w = (x1 - x0) / n
    for i in range(n):  # each character: a stem and, at random, a bar across or a bowl
        a = int(x0 + i * w + 0.2 * w)
        b = int(x0 + (i + 1) * w - 0.2 * w)
        img[int(0.2 * s) : int(0.8 * s), a : a + max(1, (b - a) // 3)] = ink
        if rng.random() < 0.5:
            img[int(0.45 * s) : int(0.55 * s), a:b] = ink
        else:
            img[int(0.2 * s) : int(0.3 * s), a:b] = ink
            img[int(0.7 * s) : int(0.8 * s), a:b] = ink
    return cv2.GaussianBlur(np.clip(img, 0, 255).astype(np.uint8), (0, 0), 0.7)


def lamp(rng: np.random.Generator, rgb: tuple[float, float, float]) -> np.ndarray:
    """A lamp lens: its colour, brighter towards the middle, with a darker rim."""
    s = TEXTURE_SIZE_PX
    v, u = np.mgrid[0:s, 0:s].astype(np.float32) / (s - 1) * 2 - 1
    r2 = np.clip(u**2 + v**2, 0, 2) / 2
    shade = 1.0 - 0.45 * r2 + 0.05 * (smooth_noise(rng, s, octaves=2, first_cells=4, decay=0.5) - 0.5)
    img = np.asarray(rgb, np.float32)[None, None] * shade[..., None] * 255.0
    return np.clip(img, 0, 255).astype(np.uint8)
