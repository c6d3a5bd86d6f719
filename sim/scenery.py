"""Static scenery: textured road with lane markings, roadside structure at all depths.

``build_scenery`` returns the scenery as data (``Scenery``: textures by name, shapes by
material); :meth:`sim.world.World.add_scenery` turns it into PyBullet bodies (this module
knows no world).

Convention: world frame (z up, x along the road, y left). Lane k (k = 0 is the ego's
lane, positive k to the left) has its centre at y = k * lane_width_m. Everything here is
static, so its motion between frames is the identity (see :mod:`sim.ground_truth`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from scenarios.road import RoadConfig  # noqa: F401  (re-exported: the world's callers import it here)
from sim.textures import VARIANTS


@dataclass(frozen=True)
class StaticShape:
    """A static box (``size_m`` = half extents [m]) or sphere (``size_m`` = (radius [m],))."""

    kind: str  # "box" or "sphere"
    center_m: tuple[float, float, float]
    size_m: tuple[float, ...]

    @classmethod
    def box(cls, center_m, half_extents_m) -> StaticShape:
        return cls("box", tuple(map(float, center_m)), tuple(map(float, half_extents_m)))

    @classmethod
    def sphere(cls, center_m, radius_m: float) -> StaticShape:
        return cls("sphere", tuple(map(float, center_m)), (float(radius_m),))


@dataclass(frozen=True)
class TextureRef:
    """A texture of the world's bank (``sim.textures.TextureBank``): kind and variant."""

    kind: str
    variant: int  # in [0, VARIANTS)


@dataclass
class StaticGroup:
    """Static shapes of one material: a texture (None: plain colour) and a colour."""

    texture: TextureRef | None
    rgb: tuple[float, ...]
    shapes: list[StaticShape] = field(default_factory=list)


@dataclass
class Scenery:
    """Static bodies as data: ``textures`` in the order the scenery asked for them (the
    world loads them in that order), ``groups`` per material in first-use order."""

    textures: list[TextureRef] = field(default_factory=list)
    groups: list[StaticGroup] = field(default_factory=list)


class _Builder:
    """Collects texture requests and shapes grouped by material."""

    def __init__(self) -> None:
        self.scenery = Scenery()
        self._groups: dict[tuple[TextureRef | None, tuple[float, ...]], StaticGroup] = {}

    def texture(self, kind: str, variant: int) -> TextureRef:
        ref = TextureRef(kind, int(variant) % VARIANTS)
        self.scenery.textures.append(ref)
        return ref

    def _group(self, texture: TextureRef | None, rgb) -> StaticGroup:
        key = (texture, tuple(rgb))
        if key not in self._groups:
            self._groups[key] = StaticGroup(texture, key[1])
            self.scenery.groups.append(self._groups[key])
        return self._groups[key]

    def box(self, center_m, half_extents_m, texture: TextureRef | None, rgb=(1.0, 1.0, 1.0)) -> None:
        self._group(texture, rgb).shapes.append(StaticShape.box(center_m, half_extents_m))

    def sphere(self, center_m, radius_m: float, texture: TextureRef | None) -> None:
        self._group(texture, (1.0, 1.0, 1.0)).shapes.append(StaticShape.sphere(center_m, radius_m))


def build_scenery(road: RoadConfig, rng: np.random.Generator) -> Scenery:
    """The road, markings and roadside objects of ``road`` (static bodies), drawn from ``rng``."""
    m = _Builder()
    x0, x1 = road.x_start_m, road.x_end_m
    yl, yr = road.y_left_edge_m, road.y_right_edge_m
    road_w = yl - yr
    v = int(rng.integers(VARIANTS))
    asphalt = [m.texture("asphalt", v + i) for i in range(2)]
    grass = [m.texture("grass", v)] * 2
    concrete = m.texture("concrete", v)
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
    _roadside(m, road, rng)
    return m.scenery


def _roadside(m: _Builder, road: RoadConfig, rng: np.random.Generator) -> None:
    """Poles, signs, trees and buildings on both sides, at several lateral depths."""
    v = int(rng.integers(VARIANTS))
    metal = m.texture("metal", v)
    bark = m.texture("bark", v)
    leaves = [m.texture("foliage", v + i) for i in range(2)]
    facades = [m.texture("facade", v + i) for i in range(3)]
    sign = m.texture("sign", v)
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
