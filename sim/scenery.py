"""Static scenery: textured road with lane markings, roadside structure at all depths.

Convention: world frame (z up, x along the road, y left). Lane k (k = 0 is the ego's
lane, positive k to the left) has its centre at y = k * lane_width_m. Everything here is
static, so its motion between frames is the identity (see :mod:`sim.ground_truth`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from sim.textures import VARIANTS

if TYPE_CHECKING:  # pragma: no cover
    from sim.world import World


@dataclass(frozen=True)
class RoadConfig:
    """Straight road layout [m]."""

    lanes_left: int = 1  # lanes left of the ego's lane
    lanes_right: int = 1  # lanes right of the ego's lane
    lane_width_m: float = 3.5
    x_start_m: float = -60.0
    x_end_m: float = 600.0
    segment_m: float = 20.0  # road/barrier tile length (keeps texture scale sane)
    roadside_spacing_m: float = 25.0  # mean spacing of poles/trees/buildings per side
    barrier: bool = True
    buildings: bool = True
    markings_max_x_m: float | None = None  # no dashed markings beyond this x [m] (None: whole road)

    def __post_init__(self) -> None:
        if self.lanes_left < 0 or self.lanes_right < 0 or self.lanes_left + self.lanes_right > 6:
            raise ValueError(f"RoadConfig lanes_left={self.lanes_left}, lanes_right={self.lanes_right}: need 0..6 in total")
        if not 2.5 <= self.lane_width_m <= 5.0:
            raise ValueError(f"RoadConfig.lane_width_m = {self.lane_width_m} outside [2.5, 5.0] m")
        if not self.x_end_m > self.x_start_m + self.segment_m:
            raise ValueError(f"RoadConfig x range [{self.x_start_m}, {self.x_end_m}] m is too short")

    @property
    def y_left_edge_m(self) -> float:
        return (self.lanes_left + 0.5) * self.lane_width_m

    @property
    def y_right_edge_m(self) -> float:
        return -(self.lanes_right + 0.5) * self.lane_width_m

    def lane_center_y_m(self, lane: int) -> float:
        if not -self.lanes_right <= lane <= self.lanes_left:
            raise ValueError(f"lane {lane} does not exist (lanes {-self.lanes_right}..{self.lanes_left})")
        return lane * self.lane_width_m


@dataclass(frozen=True)
class StaticShape:
    """A static box (``size_m`` = half extents [m]) or sphere (``size_m`` = (radius [m],))."""

    kind: str  # "box" or "sphere"
    center_m: tuple[float, float, float]
    size_m: tuple[float, ...]

    @classmethod
    def box(cls, center_m, half_extents_m) -> "StaticShape":
        return cls("box", tuple(map(float, center_m)), tuple(map(float, half_extents_m)))

    @classmethod
    def sphere(cls, center_m, radius_m: float) -> "StaticShape":
        return cls("sphere", tuple(map(float, center_m)), (float(radius_m),))


class _Materials:
    """Static shapes grouped by material (texture id, colour), in first-use order."""

    def __init__(self) -> None:
        self.groups: dict[tuple[int | None, tuple[float, ...]], list[StaticShape]] = {}

    def box(self, center_m, half_extents_m, texture_id: int | None, rgb=(1.0, 1.0, 1.0)) -> None:
        self.groups.setdefault((texture_id, tuple(rgb)), []).append(StaticShape.box(center_m, half_extents_m))

    def sphere(self, center_m, radius_m: float, texture_id: int | None) -> None:
        self.groups.setdefault((texture_id, (1.0, 1.0, 1.0)), []).append(StaticShape.sphere(center_m, radius_m))

    def add_to(self, world: World) -> None:
        for (texture_id, rgb), shapes in self.groups.items():
            world.add_static_shapes(shapes, texture_id, rgb)


def build_scenery(world: World, road: RoadConfig, rng: np.random.Generator) -> None:
    """Add the road, markings and roadside objects to ``world`` (static bodies)."""
    m = _Materials()
    x0, x1 = road.x_start_m, road.x_end_m
    yl, yr = road.y_left_edge_m, road.y_right_edge_m
    road_w = yl - yr
    v = int(rng.integers(VARIANTS))
    asphalt = [world.texture("asphalt", v + i) for i in range(2)]
    grass = [world.texture("grass", v)] * 2
    concrete = world.texture("concrete", v)
    n_seg = int(np.ceil((x1 - x0) / road.segment_m))
    for i in range(n_seg):
        xc = x0 + (i + 0.5) * road.segment_m
        m.box((xc, (yl + yr) / 2, -0.05), (road.segment_m / 2, road_w / 2, 0.05), asphalt[i % 2])
        for side, edge in ((1, yl), (-1, yr)):  # verges, 30 m wide
            m.box((xc, edge + side * 15.0, -0.06), (road.segment_m / 2, 15.0, 0.05), grass[(i + side) % 2])
        if road.barrier:
            for edge, side in ((yl, 1), (yr, -1)):
                m.box((xc, edge + side * 1.2, 0.45), (road.segment_m / 2 - 0.05, 0.15, 0.35), concrete)
    # Lane markings: solid edges, dashed separators (3 m dash, 9 m gap).
    white = (0.95, 0.95, 0.95)
    for edge in (yl - 0.15, yr + 0.15):
        for i in range(n_seg):
            xc = x0 + (i + 0.5) * road.segment_m
            m.box((xc, edge, 0.003), (road.segment_m / 2, 0.075, 0.003), None, white)
    for k in range(-road.lanes_right, road.lanes_left):
        y = (k + 0.5) * road.lane_width_m
        for xd in np.arange(x0, x1 if road.markings_max_x_m is None else min(x1, road.markings_max_x_m), 12.0):
            m.box((xd + 1.5, y, 0.003), (1.5, 0.075, 0.003), None, white)
    _roadside(world, m, road, rng)
    m.add_to(world)


def _roadside(world: World, m: _Materials, road: RoadConfig, rng: np.random.Generator) -> None:
    """Poles, signs, trees and buildings on both sides, at several lateral depths."""
    v = int(rng.integers(VARIANTS))
    metal = world.texture("metal", v)
    bark = world.texture("bark", v)
    leaves = [world.texture("foliage", v + i) for i in range(2)]
    facades = [world.texture("facade", v + i) for i in range(3)]
    sign = world.texture("sign", v)
    for side, edge in ((1, road.y_left_edge_m), (-1, road.y_right_edge_m)):
        x = road.x_start_m + rng.uniform(0, road.roadside_spacing_m)
        while x < road.x_end_m:
            kind = rng.choice(["pole", "tree", "tree", "sign", "building", "building"])
            if kind == "pole":
                y = edge + side * rng.uniform(2.0, 3.0)
                m.box((x, y, 4.0), (0.12, 0.12, 4.0), metal)
            elif kind == "sign":
                y = edge + side * rng.uniform(2.0, 3.5)
                m.box((x, y, 1.2), (0.06, 0.06, 1.2), metal)
                m.box((x, y, 2.9), (0.05, rng.uniform(0.6, 1.5), rng.uniform(0.4, 0.7)), sign)
            elif kind == "tree":
                y = edge + side * rng.uniform(3.0, 12.0)
                h = rng.uniform(2.0, 4.0)
                m.box((x, y, h / 2), (0.2, 0.2, h / 2), bark)
                r = rng.uniform(1.5, 3.0)
                m.sphere((x, y, h + r * 0.8), r, leaves[int(rng.integers(2))])
            elif road.buildings:
                depth, width, height = rng.uniform(6, 20), rng.uniform(8, 25), rng.uniform(4, 20)
                y = edge + side * (rng.uniform(12.0, 40.0) + depth / 2)
                m.box((x, y, height / 2), (width / 2, depth / 2, height / 2), facades[int(rng.integers(3))])
            x += rng.uniform(0.5, 1.5) * road.roadside_spacing_m
