"""Vehicle actors of scenario files: their fields, checks and lane changes (see
``scenarios.spec`` for the file format)."""

from __future__ import annotations

from dataclasses import dataclass, fields

from scenarios.checks import check_keys, check_not_list, fail, integer, number
from scenarios.road import RoadConfig
from scenarios.vehicle_classes import VEHICLE_CLASSES

DIRECTIONS = ("same", "oncoming", "from_left", "from_right")


@dataclass(frozen=True)
class LaneChange:
    start_s: float
    duration_s: float
    to_lane: int


@dataclass(frozen=True)
class ActorSpec:
    vehicle: str = "car"
    lane: int = 0
    direction: str = "same"
    speed_kph: float = 0.0
    overlap_pct: float = 100.0
    headway_s: float | None = None
    headway_m: float | None = None
    decel_mps2: float = 0.0
    brake_onset_s: float = 0.0
    accel_mps2: float = 0.0
    lane_change: LaneChange | None = None
    offset_s: float | None = None  # placed to meet the ego's path this long before it (junctions)


ACTOR_KEYS = {f.name for f in fields(ActorSpec)}
LC_KEYS = {f.name for f in fields(LaneChange)}


def vehicle_actor(a: dict, k: str, src: str, road: RoadConfig, ego_speed_kph: float, duration: float) -> ActorSpec:
    vehicle = a.get("vehicle", "car")
    if vehicle not in VEHICLE_CLASSES:
        raise fail(src, f"{k}.vehicle", vehicle, f"unknown vehicle (known: {', '.join(sorted(VEHICLE_CLASSES))})")
    lane = integer(src, f"{k}.lane", a.get("lane", 0), -road.lanes_right, road.lanes_left)
    direction = a.get("direction", "same")
    if direction not in DIRECTIONS:
        raise fail(src, f"{k}.direction", direction, f"must be one of {', '.join(DIRECTIONS)}")
    if direction in ("from_left", "from_right") and road.junction_m is None:
        raise fail(src, f"{k}.direction", direction, "a crossing car leaves the road network: set road.junction_m")
    hs, hm, off = a.get("headway_s"), a.get("headway_m"), a.get("offset_s")
    if sum(v is not None for v in (hs, hm, off)) != 1:
        raise fail(src, f"{k}.headway_s/headway_m/offset_s", (hs, hm, off), "give exactly one of them")
    if direction in ("from_left", "from_right") and off is None:
        raise fail(src, f"{k}.offset_s", off, "a crossing car is timed by offset_s")
    if off is not None:
        number(src, f"{k}.offset_s", off, -10.0, 30.0)
        if ego_speed_kph == 0 or a.get("speed_kph", 0.0) == 0:
            raise fail(src, f"{k}.offset_s", off, "timing by offset_s needs a moving ego and a moving target")
    if hs is not None:
        number(src, f"{k}.headway_s", hs, 0.0, 60.0, lo_open=True)
        if ego_speed_kph == 0:
            raise fail(src, f"{k}.headway_s", hs, "a time headway needs a moving ego (use headway_m)")
    if hm is not None:
        number(src, f"{k}.headway_m", hm, 0.0, 500.0, lo_open=True)
    decel = number(src, f"{k}.decel_mps2", a.get("decel_mps2", 0.0), 0.0, 12.0)
    accel = number(src, f"{k}.accel_mps2", a.get("accel_mps2", 0.0), 0.0, 6.0)
    if decel > 0 and accel > 0:
        raise fail(src, f"{k}.accel_mps2", accel, "cannot be combined with decel_mps2")
    return ActorSpec(
        vehicle=vehicle,
        lane=lane,
        direction=direction,
        speed_kph=number(src, f"{k}.speed_kph", a.get("speed_kph", 0.0), 0.0, 200.0),
        overlap_pct=number(src, f"{k}.overlap_pct", a.get("overlap_pct", 100.0), -100.0, 100.0),
        headway_s=None if hs is None else float(hs),
        headway_m=None if hm is None else float(hm),
        decel_mps2=decel,
        brake_onset_s=number(src, f"{k}.brake_onset_s", a.get("brake_onset_s", 0.0), 0.0, duration),
        accel_mps2=accel,
        lane_change=_lane_change(a.get("lane_change"), k, src, road, duration),
        offset_s=None if off is None else float(off),
    )


def _lane_change(lc_raw, k: str, src: str, road: RoadConfig, duration: float) -> LaneChange | None:
    if lc_raw is None:
        return None
    check_keys(src, f"{k}.lane_change", lc_raw, LC_KEYS)
    for lk, lv in lc_raw.items():
        check_not_list(src, f"{k}.lane_change.{lk}", lv)
    return LaneChange(
        start_s=number(src, f"{k}.lane_change.start_s", lc_raw.get("start_s", 0.0), 0.0, duration),
        duration_s=number(src, f"{k}.lane_change.duration_s", lc_raw.get("duration_s", 2.0), 0.5, 10.0),
        to_lane=integer(src, f"{k}.lane_change.to_lane", lc_raw.get("to_lane", 0), -road.lanes_right, road.lanes_left),
    )
