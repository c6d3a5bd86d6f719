"""Vehicle classes, their real-world sizes, and their multi-part PyBullet bodies.

Convention: a vehicle body's frame has its origin on the ground under the centre of
its footprint, x forward, y left, z up. The footprint is ``length_m x width_m``; the
lower body box spans exactly that footprint, so its rear face lies at x = -length/2
(the rear bumper plane used for bumper-to-bumper gaps).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from scenarios.vehicle_classes import EGO_SIZE_M, VEHICLE_CLASSES  # noqa: F401  (re-exported)

PALETTE = [
    (0.8, 0.1, 0.1),
    (0.1, 0.2, 0.7),
    (0.9, 0.9, 0.9),
    (0.15, 0.15, 0.15),
    (0.6, 0.6, 0.65),
    (0.1, 0.5, 0.2),
    (0.9, 0.6, 0.1),
    (0.5, 0.1, 0.5),
]

WHEEL_RADIUS_M = 0.32
WHEEL_WIDTH_M = 0.22
GROUND_CLEARANCE_M = 0.22


@dataclass(frozen=True)
class VehicleSpec:
    kind: str
    length_m: float
    width_m: float
    height_m: float
    palette_index: int = 0  # body colour: PALETTE[palette_index]

    def __post_init__(self) -> None:
        if self.kind not in VEHICLE_CLASSES and self.kind != "ego":
            raise ValueError(f"unknown vehicle kind {self.kind!r}; known: {sorted(VEHICLE_CLASSES)}")
        if not 0 <= self.palette_index < len(PALETTE):
            raise ValueError(f"VehicleSpec.palette_index = {self.palette_index} outside [0, {len(PALETTE) - 1}]")
        for name in ("length_m", "width_m", "height_m"):
            if not getattr(self, name) > 0:
                raise ValueError(f"VehicleSpec.{name} must be > 0, got {getattr(self, name)}")


def sample_spec(rng: np.random.Generator, kind: str) -> VehicleSpec:
    """Draw a size inside the class's range and a colour from the palette."""
    if kind not in VEHICLE_CLASSES:
        raise ValueError(f"unknown vehicle kind {kind!r}; known: {sorted(VEHICLE_CLASSES)}")
    (l0, l1), (w0, w1), (h0, h1) = VEHICLE_CLASSES[kind]
    palette_index = int(rng.integers(len(PALETTE)))
    return VehicleSpec(
        kind, float(rng.uniform(l0, l1)), float(rng.uniform(w0, w1)), float(rng.uniform(h0, h1)), palette_index
    )


@dataclass(frozen=True)
class Part:
    """A box or cylinder in the vehicle's body frame."""

    shape: str  # "box" | "wheel"
    center_m: tuple[float, float, float]
    half_extents_m: tuple[float, float, float]  # for a wheel: (radius, half width, radius)
    texture: str  # "paint" | "glass" | "tyre", and on a dressed vehicle "plate" | "tail_lamp" | "head_lamp"


#: the fittings of a dressed vehicle (``parts(..., dressed=True)``): thin boxes standing
#: FITTING_PROUD_M proud of the body's end faces (1-5 mm beyond the footprint)
PLATE_SIZE_M = (0.52, 0.11)  # (width, height) of a number plate, EU size
LAMP_SIZE_M = (0.24, 0.12)  # (width, height) of a head or tail lamp
FITTING_PROUD_M = (0.001, 0.005)  # [m] from, to beyond the end face


def parts(spec: VehicleSpec, dressed: bool = False) -> list[Part]:
    """Lower body on the full footprint, cabin (or cargo box) on top, four wheels; with
    ``dressed`` also a number plate and two lamps on each end (tail lamps at the rear, head
    lamps at the front), each a thin box just proud of the end face."""
    L, W, H = spec.length_m, spec.width_m, spec.height_m
    truck = spec.kind == "truck"
    van = spec.kind == "van"
    body_top = GROUND_CLEARANCE_M + (0.45 * H if not truck else 0.35 * H)
    out = [
        Part(
            "box",
            (0.0, 0.0, (GROUND_CLEARANCE_M + body_top) / 2),
            (L / 2, W / 2, (body_top - GROUND_CLEARANCE_M) / 2),
            "paint",
        )
    ]
    if truck:
        cab_len = 2.2
        out.append(
            Part(
                "box",
                (L / 2 - cab_len / 2, 0.0, (body_top + H * 0.85) / 2),
                (cab_len / 2, W / 2 * 0.98, (H * 0.85 - body_top) / 2),
                "glass",
            )
        )
        box_len = L - cab_len - 0.3
        out.append(
            Part(
                "box",
                (-L / 2 + box_len / 2, 0.0, (body_top + H) / 2),
                (box_len / 2, W / 2, (H - body_top) / 2),
                "paint",
            )
        )
    else:
        cab_len = L * (0.8 if van else 0.52)
        cab_x = -L * (0.06 if van else 0.08)
        out.append(
            Part("box", (cab_x, 0.0, (body_top + H) / 2), (cab_len / 2, W / 2 * 0.92, (H - body_top) / 2), "glass")
        )
    axle = L / 2 - max(0.8, 0.17 * L)
    for x in (axle, -axle):
        for side in (1, -1):
            y = side * (W / 2 - WHEEL_WIDTH_M / 2)
            out.append(
                Part("wheel", (x, y, WHEEL_RADIUS_M), (WHEEL_RADIUS_M, WHEEL_WIDTH_M / 2, WHEEL_RADIUS_M), "tyre")
            )
    if dressed:
        out += _fittings(L, W, GROUND_CLEARANCE_M, body_top)
    return out


def _fittings(L: float, W: float, bottom: float, top: float) -> list[Part]:
    """Plates low in the middle of each end face, lamps high at its corners."""
    a, b = FITTING_PROUD_M
    half_t = (b - a) / 2
    x_face = L / 2 + a + half_t
    plate_z = bottom + 0.3 * (top - bottom)
    lamp_z = bottom + 0.72 * (top - bottom)
    lamp_y = W / 2 - 0.05 - LAMP_SIZE_M[0] / 2
    out = []
    for sign, lamp in ((-1, "tail_lamp"), (1, "head_lamp")):
        x = sign * x_face
        out.append(Part("box", (x, 0.0, plate_z), (half_t, PLATE_SIZE_M[0] / 2, PLATE_SIZE_M[1] / 2), "plate"))
        for side in (1, -1):
            out.append(Part("box", (x, side * lamp_y, lamp_z), (half_t, LAMP_SIZE_M[0] / 2, LAMP_SIZE_M[1] / 2), lamp))
    return out


_CORNERS = np.array([[1, 1], [1, -1], [-1, -1], [-1, 1]])  # a footprint's corners in half extents, in order


def footprint_corners(x_m: float, y_m: float, heading_rad: float, length_m: float, width_m: float) -> np.ndarray:
    """(4, 2) corners of an oriented footprint rectangle in the world plane."""
    c, s = math.cos(heading_rad), math.sin(heading_rad)
    local = _CORNERS * [length_m / 2, width_m / 2]
    R = np.array([[c, -s], [s, c]])
    return local @ R.T + [x_m, y_m]


def footprint_corners_many(x_m, y_m, heading_rad, length_m: float, width_m: float) -> np.ndarray:
    """(N, 4, 2): ``footprint_corners`` of N poses at once ((N,) arrays), one footprint size."""
    c, s = np.cos(heading_rad), np.sin(heading_rad)
    local = _CORNERS * [length_m / 2, width_m / 2]
    R = np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)  # (N, 2, 2)
    return np.einsum("nij,kj->nki", R, local) + np.stack([x_m, y_m], -1)[:, None, :]


def footprints_overlap(a: np.ndarray, b: np.ndarray) -> bool:
    """Separating-axis test for two convex polygons given as (N, 2) corners."""
    for poly in (a, b):
        edges = np.roll(poly, -1, axis=0) - poly
        for ex, ey in edges:
            axis = np.array([-ey, ex])
            pa, pb = a @ axis, b @ axis
            if pa.max() < pb.min() or pb.max() < pa.min():
                return False
    return True


def footprints_overlap_many(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(N,) bool: ``footprints_overlap`` of N pairs of (N, 4, 2) footprints at once."""
    out = np.ones(len(a), dtype=bool)
    for poly in (a, b):
        edges = np.roll(poly, -1, axis=1) - poly  # (N, 4, 2)
        axes = np.stack([-edges[..., 1], edges[..., 0]], -1)  # (N, 4, 2)
        pa = np.einsum("nkd,njd->nkj", axes, a)
        pb = np.einsum("nkd,njd->nkj", axes, b)
        out &= ~((pa.max(-1) < pb.min(-1)) | (pb.max(-1) < pa.min(-1))).any(-1)
    return out
