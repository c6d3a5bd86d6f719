"""Vulnerable road users: pedestrian and cyclist targets as articulated rigid parts.

Each target is a few rigid parts, each its own PyBullet body with its own pose, so that
the per-pixel ground truth (:mod:`sim.ground_truth`) stays exact on a swinging leg or a
turning wheel: every pixel moves with the motion of the part it lies on.

Convention: a target's body frame has its origin on the ground under the centre of its
footprint, x along its direction of travel, y left, z up (as a vehicle's, see
:mod:`sim.vehicles`). A part's frame has its origin at the part's pivot (a hip, a
shoulder, an axle; the body origin for the rigid trunk); ``part_poses`` gives
world_T_part (4x4) for every part, from the body's planar pose and the distance it has
travelled [m], which sets the gait phase and the wheels' angle.

Sizes follow the Euro NCAP targets: the adult pedestrian target (EPTa) 1.8 m tall, the
child (EPTc) 1.15 m, the bicyclist target (EBTa) a 1.9 m bicycle with its rider.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from scenarios.road_users import (  # noqa: F401  (ADULT_HEIGHT_M, BICYCLE_LENGTH_M re-exported)
    ADULT_HEIGHT_M,
    BICYCLE_LENGTH_M,
    DEFAULT_HEIGHT_M,
    VRU_CLASS,
    VRU_KINDS,
    footprint_m,
)

BICYCLE_WHEEL_RADIUS_M = 0.35  # [m] 28-inch wheel
LEG_SWING_DEG = 25.0  # [deg] hip swing amplitude while walking
ARM_SWING_DEG = 18.0  # [deg] shoulder swing amplitude
GAIT_CYCLE_PER_HEIGHT = 0.8  # [-] distance of one gait cycle (two steps) / body height


SKIN = (0.85, 0.68, 0.55)
CLOTHES = [(0.15, 0.2, 0.45), (0.55, 0.1, 0.1), (0.2, 0.35, 0.2), (0.85, 0.8, 0.7), (0.25, 0.25, 0.25)]
TROUSERS = [(0.1, 0.1, 0.15), (0.3, 0.25, 0.2), (0.15, 0.2, 0.35)]


@dataclass(frozen=True)
class VruSpec:
    """A pedestrian ('adult' or 'child') or a 'cyclist', its height [m] and colours."""

    kind: str
    height_m: float
    clothes_index: int = 0
    trousers_index: int = 0

    def __post_init__(self) -> None:
        if self.kind not in VRU_KINDS:
            raise ValueError(f"unknown road user kind {self.kind!r}; known: {', '.join(VRU_KINDS)}")
        if not 0.5 <= self.height_m <= 2.2:
            raise ValueError(f"VruSpec.height_m = {self.height_m} outside [0.5, 2.2] m")

    @property
    def length_m(self) -> float:
        """[m] the contact footprint along the direction of travel."""
        return footprint_m(self.kind, self.height_m)[0]

    @property
    def width_m(self) -> float:
        """[m] the contact footprint across the direction of travel."""
        return footprint_m(self.kind, self.height_m)[1]

    @property
    def cls(self) -> str:
        return VRU_CLASS[self.kind]


def vru_spec(kind: str, rng: np.random.Generator, height_m: float | None = None) -> VruSpec:
    """A target of ``kind`` with colours drawn from ``rng`` (height: the Euro NCAP target's)."""
    if kind not in DEFAULT_HEIGHT_M:
        raise ValueError(f"unknown road user kind {kind!r}; known: {', '.join(VRU_KINDS)}")
    return VruSpec(
        kind,
        float(DEFAULT_HEIGHT_M[kind] if height_m is None else height_m),
        int(rng.integers(len(CLOTHES))),
        int(rng.integers(len(TROUSERS))),
    )


@dataclass(frozen=True)
class Box:
    """A box in its part's frame: centre and half extents [m], colour."""

    center_m: tuple[float, float, float]
    half_m: tuple[float, float, float]
    rgb: tuple[float, float, float]


@dataclass(frozen=True)
class VruPart:
    """One rigid part: its boxes (or a wheel: ``wheel_radius_m`` > 0, a cylinder about the
    part frame's y axis) and its pivot in the body frame [m]."""

    name: str
    pivot_m: tuple[float, float, float]
    boxes: tuple[Box, ...] = ()
    wheel_radius_m: float = 0.0
    wheel_width_m: float = 0.0


def parts(spec: VruSpec) -> list[VruPart]:
    """The rigid parts of a target, in the order ``part_poses`` poses them."""
    return _cyclist_parts(spec) if spec.kind == "cyclist" else _pedestrian_parts(spec)


def _pedestrian_parts(spec: VruSpec) -> list[VruPart]:
    h = spec.height_m
    shirt, trousers = CLOTHES[spec.clothes_index], TROUSERS[spec.trousers_index]
    hip_z, shoulder_z = 0.52 * h, 0.81 * h
    leg_len, arm_len = hip_z, 0.36 * h
    trunk = VruPart(
        "trunk",
        (0.0, 0.0, 0.0),
        (
            Box(
                (0.0, 0.0, (hip_z + shoulder_z) / 2 + 0.01 * h), (0.065 * h, 0.12 * h, (shoulder_z - hip_z) / 2), shirt
            ),
            Box((0.0, 0.0, 0.87 * h), (0.06 * h, 0.055 * h, 0.03 * h), SKIN),  # neck and chin
            Box((0.0, 0.0, 0.94 * h), (0.065 * h, 0.06 * h, 0.06 * h), SKIN),  # head
        ),
    )
    out = [trunk]
    for side, name in ((1, "left_leg"), (-1, "right_leg")):
        out.append(
            VruPart(
                name,
                (0.0, side * 0.06 * h, hip_z),
                (
                    Box((0.0, 0.0, -leg_len / 2), (0.045 * h, 0.045 * h, leg_len / 2), trousers),
                    Box((0.03 * h, 0.0, -leg_len + 0.012 * h), (0.07 * h, 0.04 * h, 0.012 * h), (0.1, 0.1, 0.1)),
                ),
            )
        )
    for side, name in ((1, "left_arm"), (-1, "right_arm")):
        out.append(
            VruPart(
                name,
                (0.0, side * 0.15 * h, shoulder_z),
                (Box((0.0, 0.0, -arm_len / 2), (0.03 * h, 0.028 * h, arm_len / 2), shirt),),
            )
        )
    return out


def _cyclist_parts(spec: VruSpec) -> list[VruPart]:
    h = spec.height_m
    r = BICYCLE_WHEEL_RADIUS_M
    axle_x = BICYCLE_LENGTH_M / 2 - r
    shirt, trousers = CLOTHES[spec.clothes_index], TROUSERS[spec.trousers_index]
    frame_rgb = (0.7, 0.7, 0.75)
    saddle_z = 0.55 * h
    body = VruPart(
        "bicycle_and_rider",
        (0.0, 0.0, 0.0),
        (
            Box((0.0, 0.0, r + 0.15), (axle_x * 0.8, 0.02, 0.02), frame_rgb),  # top tube
            Box((-0.1, 0.0, r + 0.02), (axle_x * 0.6, 0.02, 0.02), frame_rgb),  # down tube
            Box((-0.15, 0.0, (r + saddle_z) / 2), (0.02, 0.02, (saddle_z - r) / 2), frame_rgb),  # seat tube
            Box((axle_x - 0.05, 0.0, r + 0.3), (0.02, 0.02, 0.3), frame_rgb),  # fork and stem
            Box((axle_x - 0.1, 0.0, r + 0.6), (0.03, 0.25, 0.015), (0.1, 0.1, 0.1)),  # handlebar
            Box((0.0, 0.0, saddle_z + 0.2 * h), (0.07 * h, 0.11 * h, 0.14 * h), shirt),  # rider's torso
            Box((0.06 * h, 0.0, saddle_z + 0.42 * h), (0.06 * h, 0.055 * h, 0.065 * h), SKIN),  # head
            Box((0.1 * h, 0.0, saddle_z + 0.24 * h), (0.14 * h, 0.12 * h, 0.025 * h), shirt),  # arms
            Box((-0.05, 0.06 * h, saddle_z - 0.13 * h), (0.04 * h, 0.035 * h, 0.16 * h), trousers),  # legs
            Box((0.05, -0.06 * h, saddle_z - 0.13 * h), (0.04 * h, 0.035 * h, 0.16 * h), trousers),
        ),
    )
    wheels = [
        VruPart(n, (x, 0.0, r), wheel_radius_m=r, wheel_width_m=0.05)
        for n, x in (("front_wheel", axle_x), ("rear_wheel", -axle_x))
    ]
    return [body, *wheels]


def _rot_y(angle_rad: float) -> np.ndarray:
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def joint_angles(spec: VruSpec, travelled_m: float) -> list[float]:
    """Rotation [rad] of each part about its pivot's y axis (the body's lateral axis) after
    travelling ``travelled_m``: legs and arms swing in opposite phase over a gait cycle of
    ``GAIT_CYCLE_PER_HEIGHT * height``; wheels roll (angle = distance / radius, the top moving
    forward); the trunk stays upright."""
    if spec.kind == "cyclist":
        phi = travelled_m / BICYCLE_WHEEL_RADIUS_M
        return [0.0, phi, phi]
    ph = 2 * math.pi * travelled_m / (GAIT_CYCLE_PER_HEIGHT * spec.height_m)
    leg, arm = math.radians(LEG_SWING_DEG) * math.sin(ph), math.radians(ARM_SWING_DEG) * math.sin(ph)
    # a positive rotation about y swings the lower end backwards; the left leg leads with -leg
    return [0.0, -leg, leg, arm, -arm]


def part_poses(spec: VruSpec, pose: tuple[float, float, float], travelled_m: float) -> list[np.ndarray]:
    """world_T_part (4x4) of every part of ``parts(spec)``: the body at planar ``pose``
    (x [m], y [m], heading [rad]) after travelling ``travelled_m`` [m]."""
    x, y, heading = pose
    c, s = math.cos(heading), math.sin(heading)
    world_T_body = np.eye(4)
    world_T_body[:2, :2] = [[c, -s], [s, c]]
    world_T_body[:2, 3] = (x, y)
    out = []
    for part, angle in zip(parts(spec), joint_angles(spec, travelled_m)):
        body_T_part = np.eye(4)
        body_T_part[:3, :3] = _rot_y(angle)
        body_T_part[:3, 3] = part.pivot_m
        out.append(world_T_body @ body_T_part)
    return out
