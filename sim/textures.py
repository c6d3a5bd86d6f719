"""Procedural textures, drawn from a numpy Generator so a seed fixes every pixel.

TinyRenderer has no mip-mapping: texture detail finer than a screen pixel turns into
noise that differs between frames. The textures here are therefore smooth noise
(a few octaves, most energy at low frequency) rather than white noise.

Ground styles (``TextureBank(ground=...)``):
    ``"detailed"`` (default): asphalt and grass carry broadband noise plus anti-aliased
    patches 0.15-1.5 m across (repairs, stains, clumps), so the ground's own motion can be
    measured between frames, as on a real road. At 10 m ahead a 96 x 288 px camera sees
    about 0.4 m of road per image row, at 5 m about 0.1 m.
    ``"smooth"``: the textures of dataset version bittc_v1 (most energy at 5 m scale;
    the ground looks nearly uniform, so its motion is hard to measure).

Vehicle styles (``TextureBank(vehicles=...)``):
    ``"plain"`` (default): panel shading, a dark window band, lamps; large faces are
    nearly uniform (the vehicles of every dataset the shipped weights were trained on).
    ``"detailed"``: paint and glass also carry mid-frequency shading (dirt, reflections)
    and anti-aliased spots 6-22 cm across on a 1.8 m car face, so a vehicle's own scale
    change can be measured inside its outline, not only at its edges (an experiment:
    it did not raise the network's accuracy on actors, see the README).
    ``"mixed"``: odd texture variants detailed, even ones plain, so one world has both.
    ``"dressed"``: detailed paint; glass in window frames (the body's colour round each
    pane, a pillar, a reflection across the glass); and fittings: a number plate (white or
    yellow, a dark border and characters) and two lamps (red at the rear, white at the
    front) on each end, thin boxes just proud of the end faces (``sim.vehicles.parts``).
    ``"assorted"``: a third of the texture variants each plain, detailed and dressed.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from sim.texture_noise import TEXTURE_SIZE_PX, patches, smooth_noise, tinted  # noqa: F401  (re-exported)

GROUND_TEXTURE_SIZE_PX = 256  # a 20 m road tile: 8 cm per texel along the road
GROUND_STYLES = ("detailed", "smooth")
VEHICLE_STYLES = ("plain", "detailed", "mixed", "dressed", "assorted")
FITTING_KINDS = ("plate", "tail_lamp", "head_lamp")  # the fittings of a dressed vehicle, the same in every style
VEHICLE_KINDS = ("paint", "glass")  # the kinds a vehicle style changes


@dataclass(frozen=True)
class TextureStyle:
    """How a world looks: the ground style and the vehicle style (see the module doc)."""

    ground: str = "detailed"  # GROUND_STYLES
    vehicles: str = "plain"  # VEHICLE_STYLES

    def __post_init__(self) -> None:
        if self.ground not in GROUND_STYLES:
            raise ValueError(f"ground texture style {self.ground!r}: must be one of {GROUND_STYLES}")
        if self.vehicles not in VEHICLE_STYLES:
            raise ValueError(f"vehicle texture style {self.vehicles!r}: must be one of {VEHICLE_STYLES}")


def asphalt(rng: np.random.Generator) -> np.ndarray:
    grey = rng.uniform(0.25, 0.45)
    return tinted(rng, (grey, grey, grey * 1.02), contrast=1.1)


def detailed_ground(
    rng: np.random.Generator,
    rgb: tuple[float, float, float],
    noise_contrast: float = 1.0,
    patch_contrast: float = 0.6,
    count: int = 700,
) -> np.ndarray:
    """(256, 256, 3) uint8 ground: broadband noise (2.5 m to 0.3 m cells on a 20 m
    tile, flat spectrum) plus ``count`` patches 1-6 texels in radius."""
    s = GROUND_TEXTURE_SIZE_PX
    n = smooth_noise(rng, s, octaves=4, first_cells=8, decay=0.85) - 0.5
    shade = 1.0 + noise_contrast * n + patch_contrast * patches(rng, s, count, (1.0, 6.0))
    img = np.asarray(rgb, np.float32)[None, None, :] * shade[..., None]
    return np.clip(img * 255.0, 0, 255).astype(np.uint8)


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
TEXTURE_KINDS = (
    *("asphalt", "grass", "concrete", "metal", "bark", "foliage", "facade", "sign", "glass", "tyre", "paint"),
    *FITTING_KINDS,  # appended: the seeds of the kinds before stay as they were
)
VARIANTS = 6  # variants per kind (per palette colour for paint)


class TextureBank:
    """Procedural textures written once as PNG files, picked by (kind, variant).

    A bank is a pure function of its seed, so any process that builds the bank with
    the same seed renders the same pixels. Worlds load from it instead of drawing
    fresh textures, which keeps building a world cheap when many are built in a row.
    """

    def __init__(self, seed: int, directory: Path, ground: str = "detailed", vehicles: str = "plain"):
        TextureStyle(ground, vehicles)  # validates both
        self.seed = seed
        self.ground = ground
        self.vehicles = vehicles
        self.dir = Path(directory)
        self.dir.mkdir(parents=True, exist_ok=True)

    def vehicle_style(self, variant: int) -> str:
        """The style of a vehicle drawn with texture ``variant``: "mixed" and "assorted"
        resolved to plain, detailed (and dressed) by the variant."""
        variant %= VARIANTS
        if self.vehicles == "mixed":
            return "detailed" if variant % 2 else "plain"
        if self.vehicles == "assorted":
            return ("plain", "detailed", "dressed")[variant % 3]
        return self.vehicles

    def path(self, kind: str, variant: int, palette_index: int = 0) -> Path:
        if kind not in TEXTURE_KINDS:
            raise ValueError(f"unknown texture kind {kind!r}")
        variant %= VARIANTS
        if kind in FITTING_KINDS:
            style = "fitting"  # the same in every vehicle style
        elif kind in VEHICLE_KINDS:
            style = self.vehicle_style(variant)
        else:
            style = self.ground
        p = self.dir / f"{style}_{kind}_{palette_index}_{variant}.png"
        if not p.exists():
            rng = np.random.default_rng([self.seed, TEXTURE_KINDS.index(kind), palette_index, variant])
            img = _draw(kind, rng, palette_index, self.ground)
            if style in ("detailed", "dressed") and kind in ("paint", "glass"):  # after the plain one: same base
                from sim.vehicle_textures import vehicle_detail, window_frames

                img = vehicle_detail(rng, img, *((0.5, 0.35) if kind == "paint" else (0.8, 0.5)))
                if style == "dressed" and kind == "glass":
                    img = window_frames(rng, img, palette_index)
            tmp = p.with_name(f".{p.name}.{os.getpid()}.tmp.png")
            cv2.imwrite(str(tmp), cv2.cvtColor(img, cv2.COLOR_RGB2BGR))
            os.replace(tmp, p)
        return p


def _draw(kind: str, rng: np.random.Generator, palette_index: int, ground: str) -> np.ndarray:
    from sim.vehicle_textures import lamp, number_plate, vehicle_paint
    from sim.vehicles import PALETTE

    if ground == "detailed" and kind == "asphalt":
        grey = rng.uniform(0.28, 0.45)
        return detailed_ground(rng, (grey, grey, grey * 1.02))
    if ground == "detailed" and kind == "grass":
        return detailed_ground(rng, (0.3, 0.45, 0.2))
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
    if kind == "plate":
        return number_plate(rng)
    if kind == "tail_lamp":
        return lamp(rng, (0.85, 0.08, 0.06))
    if kind == "head_lamp":
        return lamp(rng, (0.97, 0.96, 0.88))
    return vehicle_paint(rng, PALETTE[palette_index])
