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


def _band(road: RoadConfig) -> tuple[float, float] | None:
    """x range [m] the cross road and its sidewalks take out of the main road's sides."""
    if road.junction_m is None:
        return None
    hw = road.cross_half_width_m + road.sidewalk_m
    return road.junction_m - hw, road.junction_m + hw


def _pieces(x0: float, x1: float, band: tuple[float, float] | None) -> list[tuple[float, float]]:
    """[x0, x1] without the junction ``band``: 0, 1 or 2 intervals [m]."""
    if band is None or x1 <= band[0] or x0 >= band[1]:
        return [(x0, x1)]
    return [(a, b) for a, b in ((x0, band[0]), (band[1], x1)) if b - a > 1e-6]


def build_scenery(road: RoadConfig, rng: np.random.Generator) -> Scenery:
    """The road, markings and roadside objects of ``road`` (static bodies), drawn from ``rng``."""
    m = _Builder()
    x0, x1 = road.x_start_m, road.x_end_m
    yl, yr = road.y_left_edge_m, road.y_right_edge_m
    road_w = yl - yr
    band = _band(road)
    sw = road.sidewalk_m
    v = int(rng.integers(VARIANTS))
    asphalt = [m.texture("asphalt", v + i) for i in range(2)]
    grass = [m.texture("grass", v)] * 2
    concrete = m.texture("concrete", v)
    n_seg = int(np.ceil((x1 - x0) / road.segment_m))
    for i in range(n_seg):
        xc = x0 + (i + 0.5) * road.segment_m
        m.box((xc, (yl + yr) / 2, -0.05), (road.segment_m / 2, road_w / 2, 0.05), asphalt[i % 2])
        for a, b in _pieces(xc - road.segment_m / 2, xc + road.segment_m / 2, band):
            xm, hx = (a + b) / 2, (b - a) / 2
            for side, edge in ((1, yl), (-1, yr)):  # sidewalks behind kerbs, then verges 30 m wide
                if sw > 0:
                    m.box((xm, edge + side * sw / 2, -0.03), (hx, sw / 2, 0.05), concrete)
                    m.box((xm, edge + side * 0.075, 0.06), (hx, 0.075, 0.06), None, KERB_RGB)
                m.box((xm, edge + side * (sw + 15.0), -0.06), (hx, 15.0, 0.05), grass[(i + side) % 2])
                if road.barrier and sw == 0:
                    m.box((xm, edge + side * 1.2, 0.45), (hx - 0.05, 0.15, 0.35), concrete)
    # Lane markings: solid edges, dashed separators (3 m dash, 9 m gap).
    white = (0.95, 0.95, 0.95)
    for edge in (yl - 0.15, yr + 0.15):
        for i in range(n_seg):
            xc = x0 + (i + 0.5) * road.segment_m
            for a, b in _pieces(xc - road.segment_m / 2, xc + road.segment_m / 2, band):
                m.box(((a + b) / 2, edge, 0.003), ((b - a) / 2, 0.075, 0.003), None, white)
    for k in range(-road.lanes_right, road.lanes_left):
        y = (k + 0.5) * road.lane_width_m
        for xd in np.arange(x0, x1 if road.markings_max_x_m is None else min(x1, road.markings_max_x_m), 12.0):
            if band is None or xd + 3.0 <= band[0] or xd >= band[1]:
                m.box((xd + 1.5, y, 0.003), (1.5, 0.075, 0.003), None, white)
    if band is not None:
        _cross_road(m, road, asphalt[0], concrete, grass[0], white)
    _roadside(m, road, rng, band)
    return m.scenery


KERB_RGB = (0.72, 0.72, 0.7)
CROSS_ROAD_M = 120.0  # [m] the cross road's length on each side of the main road


def _cross_road(m: _Builder, road: RoadConfig, asphalt, concrete, grass, white) -> None:
    """The cross road at x = junction_m: carriageway, centre line, sidewalks and verges on
    both sides of the main road, in ``segment_m`` tiles along y (as the main road's, so
    that its textures keep their scale)."""
    J, hw, sw, seg = road.junction_m, road.cross_half_width_m, road.sidewalk_m, road.segment_m
    for side, edge in ((1, road.y_left_edge_m), (-1, road.y_right_edge_m)):
        for k in range(int(np.ceil(CROSS_ROAD_M / seg))):
            y_mid = edge + side * (k + 0.5) * seg
            m.box((J, y_mid, -0.05), (hw, seg / 2, 0.05), asphalt)
            for xs in (1, -1):  # its sidewalks run on into the corners the main road's leave free
                if sw > 0:
                    m.box((J + xs * (hw + sw / 2), y_mid, -0.03), (sw / 2, seg / 2, 0.05), concrete)
                    m.box((J + xs * (hw + 0.075), y_mid, 0.06), (0.075, seg / 2, 0.06), None, KERB_RGB)
                m.box((J + xs * (hw + sw + 15.0), y_mid, -0.06), (15.0, seg / 2, 0.05), grass)
        for yd in np.arange(sw + 2.0, CROSS_ROAD_M, 12.0):
            m.box((J, edge + side * (yd + 1.5), 0.003), (0.075, 1.5, 0.003), None, white)


def _roadside(m: _Builder, road: RoadConfig, rng: np.random.Generator, band=None) -> None:
    """Poles, signs, trees and buildings on both sides, at several lateral depths (none
    where they would stand on the cross road, or on its sidewalks)."""
    v = int(rng.integers(VARIANTS))
    metal = m.texture("metal", v)
    bark = m.texture("bark", v)
    leaves = [m.texture("foliage", v + i) for i in range(2)]
    facades = [m.texture("facade", v + i) for i in range(3)]
    sign = m.texture("sign", v)
    for side, edge0 in ((1, road.y_left_edge_m), (-1, road.y_right_edge_m)):
        x = road.x_start_m + rng.uniform(0, road.roadside_spacing_m)
        while x < road.x_end_m:
            kind = rng.choice(["pole", "tree", "tree", "sign", "building", "building"])
            half = 13.0 if kind == "building" else 1.0  # the largest half width of the kind [m]
            if band is not None and band[0] - half < x < band[1] + half:
                x += rng.uniform(0.5, 1.5) * road.roadside_spacing_m
                continue
            edge = edge0 + side * road.sidewalk_m
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
