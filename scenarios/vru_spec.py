"""Road-user actors of scenario files (pedestrians, cyclists) and where they start.

An entry of ``actors`` with a ``pedestrian`` or ``cyclist`` key::

    - pedestrian: adult        # adult | child (cyclist: adult)
      path: nearside           # nearside (from the ego's right) | farside (from its left)
                               # | longitudinal (ahead, moving away) | oncoming (ahead, towards it)
      speed_kph: 5             # > 0
      impact_pct: 25           # crossing: where its path meets the ego's front, % of the ego's width
                               # from the side it comes from; longitudinal: its centre, % from the right
      lateral_m: null          # instead of impact_pct: its centre's offset from the ego's centreline (+ left)
      offset_s: 0              # reach the impact point this long before the ego's front (0: collision course)
      headway_m: null          # longitudinal/oncoming: initial gap ahead (default: closing speed x ego.conflict_s)
      start_m: null            # crossing: stand this far from the impact point until it must go
      stop_m: null             # crossing: stop this far short of the ego's side of its path (at the kerb)
      obstruction: false       # two parked cars on its side hide it (CPNCO, CBNAO)
      height_m: null           # default: the Euro NCAP target's (adult 1.8 m, child 1.15 m)

Timing: without braking the ego's front reaches the crossing line ``ego.conflict_s`` after
the start (Euro NCAP synchronises the target so that it meets the chosen impact point).
Euro NCAP's targets accelerate to speed over a short distance; here a target that must
wait (``start_m``) starts at full speed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

from scenarios.checks import fail, number
from scenarios.road import RoadConfig
from scenarios.road_users import ADULT_HEIGHT_M, DEFAULT_HEIGHT_M, footprint_m
from scenarios.vehicle_classes import EGO_SIZE_M

VRU_PATHS = ("nearside", "farside", "longitudinal", "oncoming")
STOP_DECEL_MPS2 = 2.0  # [m/s^2] a walker stopping at the kerb


@dataclass(frozen=True)
class VruActorSpec:
    kind: str  # adult | child | cyclist
    path: str
    speed_kph: float
    height_m: float
    impact_pct: float | None = None
    lateral_m: float | None = None
    offset_s: float = 0.0
    headway_m: float | None = None
    start_m: float | None = None
    stop_m: float | None = None
    obstruction: bool = False

    @property
    def footprint_m(self) -> tuple[float, float]:
        return footprint_m(self.kind, self.height_m)

    @property
    def crossing(self) -> bool:
        return self.path in ("nearside", "farside")


#: the keys an actor entry with ``pedestrian`` or ``cyclist`` may have
VRU_KEYS = {"pedestrian", "cyclist"} | {f.name for f in fields(VruActorSpec)} - {"kind"}


@dataclass(frozen=True)
class VruPlacement:
    """Where and how a road user moves: start (x, y) [m], heading [rad], speed [m/s], the
    time it starts [s], the distance after which it stops [m] (None: it keeps going)."""

    x_m: float
    y_m: float
    heading_rad: float
    speed_mps: float
    start_s: float
    stop_after_m: float | None
    crossing_x_m: float  # [m] x of its crossing line (crossing) or its initial x (longitudinal)


def is_vru_entry(a) -> bool:
    return isinstance(a, dict) and ("pedestrian" in a or "cyclist" in a)


def vru_actor(a: dict, k: str, src: str, heights: list[float]) -> VruActorSpec:
    """Validate one road-user entry (``heights``: the heights of the file's adults, for the
    check that a child is shorter)."""
    if "pedestrian" in a and "cyclist" in a:
        raise fail(src, f"{k}.pedestrian", a["pedestrian"], "give either pedestrian or cyclist")
    if "cyclist" in a:
        kind = "cyclist"
        if a["cyclist"] != "adult":
            raise fail(src, f"{k}.cyclist", a["cyclist"], "must be 'adult' (the Euro NCAP bicyclist target)")
    else:
        kind = a["pedestrian"]
        if kind not in ("adult", "child"):
            raise fail(src, f"{k}.pedestrian", kind, "must be 'adult' or 'child'")
    path = a.get("path", "nearside")
    if path not in VRU_PATHS:
        raise fail(src, f"{k}.path", path, f"must be one of {', '.join(VRU_PATHS)}")
    speed = number(src, f"{k}.speed_kph", a.get("speed_kph", 5.0), 0.0, 40.0, lo_open=True)
    height = number(src, f"{k}.height_m", a.get("height_m", DEFAULT_HEIGHT_M[kind]), 0.5, 2.2)
    if kind == "child":
        adult = min(heights, default=ADULT_HEIGHT_M)
        if height >= adult:
            raise fail(src, f"{k}.height_m", height, f"a child must be shorter than the adult ({adult:g} m)")
    pct, lat = a.get("impact_pct"), a.get("lateral_m")
    if (pct is None) == (lat is None):
        raise fail(src, f"{k}.impact_pct/lateral_m", (pct, lat), "give exactly one of them")
    opt = {}
    for key, lo, hi in (("headway_m", 0.0, 300.0), ("start_m", 0.0, 60.0), ("stop_m", 0.0, 20.0)):
        if a.get(key) is not None:
            opt[key] = number(src, f"{k}.{key}", a[key], lo, hi, lo_open=key != "stop_m")
    obstruction = a.get("obstruction", False)
    if not isinstance(obstruction, bool):
        raise fail(src, f"{k}.obstruction", obstruction, "must be true or false")
    crossing = path in ("nearside", "farside")
    for key in ("start_m", "stop_m"):
        if key in opt and not crossing:
            raise fail(src, f"{k}.{key}", opt[key], f"only a crossing road user (path nearside/farside) has {key}")
    if "headway_m" in opt and crossing:
        raise fail(src, f"{k}.headway_m", opt["headway_m"], "a crossing road user is timed by offset_s")
    return VruActorSpec(
        kind=kind,
        path=path,
        speed_kph=speed,
        height_m=height,
        impact_pct=None if pct is None else number(src, f"{k}.impact_pct", pct, 0.0, 100.0),
        lateral_m=None if lat is None else number(src, f"{k}.lateral_m", lat, -30.0, 30.0),
        offset_s=number(src, f"{k}.offset_s", a.get("offset_s", 0.0), -10.0, 30.0),
        obstruction=obstruction,
        **opt,
    )


def vru_placement(a: VruActorSpec, ego_speed_mps: float, conflict_s: float) -> VruPlacement:
    """Where road user ``a`` starts and how it moves, for an ego driving straight along
    y = 0 at ``ego_speed_mps`` from x = 0 (its centre) whose front would reach the
    crossing line ``conflict_s`` after the start."""
    ego_len, ego_w = EGO_SIZE_M[0], EGO_SIZE_M[1]
    length, width = a.footprint_m
    v = a.speed_kph / 3.6
    if a.crossing:
        d = 1.0 if a.path == "nearside" else -1.0  # +1 walks towards +y (from the ego's right)
        if a.lateral_m is not None:
            y_impact = a.lateral_m
        else:
            y_impact = -d * ego_w / 2 + d * ego_w * a.impact_pct / 100.0
        x = ego_len / 2 + ego_speed_mps * conflict_s + width / 2  # its near side on the crossing line
        arrive = conflict_s - a.offset_s
        if a.start_m is not None:
            start_s, y0 = arrive - a.start_m / v, y_impact - d * a.start_m
        else:
            start_s, y0 = 0.0, y_impact - d * v * arrive
        stop = None
        if a.stop_m is not None:  # its leading edge stops stop_m short of the ego's near side
            stop = d * ((-d * ego_w / 2 - d * a.stop_m - d * length / 2) - y0)
        return VruPlacement(x, y0, d * math.pi / 2, v, start_s, stop, x)
    y = a.lateral_m if a.lateral_m is not None else -ego_w / 2 + ego_w * a.impact_pct / 100.0
    towards = a.path == "oncoming"
    closing = ego_speed_mps + v if towards else ego_speed_mps - v
    gap = a.headway_m if a.headway_m is not None else max(closing, 0.0) * conflict_s
    x = ego_len / 2 + gap + length / 2
    return VruPlacement(x, y, math.pi if towards else 0.0, v, 0.0, None, x)


def check_placement(
    a: VruActorSpec, p: VruPlacement, k: str, src: str, road: RoadConfig, duration_s: float, conflict_s: float
) -> None:
    """Refuse a road user whose path leaves the road and its sidewalks (from its start to
    1 s after the ego would reach its line, or the end of the run), that would have to start
    before the run does, or that would stop before it moves."""
    if p.start_s < 0:
        raise fail(src, f"{k}.start_m", a.start_m, f"too far to reach the impact point in time ({p.start_s:.2f} s)")
    if p.stop_after_m is not None and p.stop_after_m <= 0:
        raise fail(src, f"{k}.stop_m", a.stop_m, "it would stop before it starts moving")
    for t in (0.0, min(duration_s, conflict_s + 1.0)):
        moving = max(t - p.start_s, 0.0)
        d = moving * p.speed_mps if p.stop_after_m is None else min(moving * p.speed_mps, p.stop_after_m)
        x, y = p.x_m + d * math.cos(p.heading_rad), p.y_m + d * math.sin(p.heading_rad)
        if not road.on_foot_area(x, y):
            where = "starts" if t == 0 else f"is at {t:g} s"
            raise fail(
                src,
                f"{k}.path",
                a.path,
                f"leaves the road network: it {where} at ({x:.1f}, {y:.1f}) m, off the "
                "road and its sidewalks (widen road.sidewalk_m, or set start_m)",
            )
