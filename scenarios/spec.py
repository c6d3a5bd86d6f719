"""Declarative scenario files: schema, validation, sweep expansion.

A scenario file (YAML) describes one family of runs in Euro NCAP terms::

    name: CCRs                       # family name
    description: Car-to-Car Rear stationary
    threat: true                     # a collision course (true) or benign (false)
    case_name: "CCRs-{ego_speed_kph}"  # one name per expanded case
    duration_s: 12
    road: {lanes_left: 1, lanes_right: 1, lane_width_m: 3.5}
    ego: {speed_kph: [10, 20, 30]}   # a list expands into a sweep
    actors:
      - vehicle: gvt                 # car | gvt | van | truck
        lane: 0                      # lane offset from the ego's lane, + = left
        direction: same              # same | oncoming
        speed_kph: 0
        overlap_pct: 100             # share of the ego's width overlapped; < 0: target on the ego's right
        headway_s: 5                 # initial gap = headway_s * ego speed (or headway_m)
        decel_mps2: 0                # target braking from brake_onset_s (Euro NCAP CCRb)
        brake_onset_s: 0
        accel_mps2: 0                # target speeding up from t = 0
        lane_change: {start_s: 1, duration_s: 2, to_lane: 0}
    traffic: 0                       # background IDM vehicles in the other lanes

Sweeps: a list expands into the cartesian product of runs only in the fields of ``ego``
and of each entry of ``actors`` (``lane_change`` too: a list of lane changes, ``null``
for none); a list anywhere else (the top-level fields, ``road``, inside
``lane_change``) is a ConfigError. In ``case_name`` a swept field is referenced by its
flattened name: ``ego_speed_kph``, ``actor0_overlap_pct``, ``actor0_headway_m``...
Headway: Euro NCAP runs start at 5 s time headway, i.e. a gap of 5 s at the ego's speed.
The gap is bumper to bumper along the road.
"""

from __future__ import annotations

import itertools
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import Any

import yaml

from bittc_core.errors import ConfigError
from scenarios.checks import check_keys, check_name, check_not_list, check_unswept, fail, integer, number
from scenarios.road import RoadConfig
from scenarios.sweep_fields import flatten_sweeps, fmt_value, set_flat
from scenarios.vehicle_classes import VEHICLE_CLASSES


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


@dataclass(frozen=True)
class EgoSpec:
    speed_kph: float = 50.0


@dataclass(frozen=True)
class ScenarioCase:
    """One fully resolved run (no lists left)."""

    family: str
    name: str
    description: str
    threat: bool
    duration_s: float
    road: RoadConfig
    ego: EgoSpec
    actors: tuple[ActorSpec, ...]
    traffic: int = 0
    source: str = ""

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["actors"] = [asdict(a) for a in self.actors]
        return d


_TOP_KEYS = {"name", "description", "threat", "case_name", "duration_s", "road", "ego", "actors", "traffic"}
_ROAD_KEYS = {f.name for f in fields(RoadConfig)}
_ROAD_COMPUTED = {"x_start_m", "x_end_m", "markings_max_x_m"}  # set by the simulator from the scenario
_ROAD_DEFAULTS = {f.name: f.default for f in fields(RoadConfig)}
_EGO_KEYS = {f.name for f in fields(EgoSpec)}
_ACTOR_KEYS = {f.name for f in fields(ActorSpec)}
_LC_KEYS = {f.name for f in fields(LaneChange)}


def load_file(path: str | Path) -> list[ScenarioCase]:
    """Parse, validate and expand one scenario file into its cases."""
    path = Path(path)
    src = str(path)
    try:
        text = path.read_text()
    except OSError as e:
        raise ConfigError(f"{src}: cannot read scenario file ({e.strerror})") from None
    try:
        raw = yaml.safe_load(text)
    except yaml.YAMLError as e:
        raise ConfigError(f"{src}: malformed YAML: {str(e).splitlines()[0]}") from None
    return expand(raw, src)


def expand(raw: Any, src: str) -> list[ScenarioCase]:
    check_keys(src, "", raw, _TOP_KEYS)
    for req in ("name", "threat", "ego"):
        if req not in raw:
            raise ConfigError(f"{src}: missing required key {req!r}")
    check_unswept(src, raw)
    check_name(src, "name", raw["name"])
    check_keys(src, "ego", raw["ego"], _EGO_KEYS)
    actors = raw.get("actors") or []
    if not isinstance(actors, list):
        raise fail(src, "actors", actors, "must be a list")
    for i, a in enumerate(actors):
        check_keys(src, f"actors[{i}]", a, _ACTOR_KEYS)
    names, values = flatten_sweeps(raw)
    for n, vs in zip(names, values):
        if len(vs) == 0:
            raise fail(src, n, vs, "an empty list expands to no run")
    template = raw.get("case_name")
    if template is None:
        template = raw["name"] + "".join(f"-{{{n}}}" for n in names)
    check_name(src, "case_name", template, template=True)
    cases = []
    for combo in itertools.product(*values) if names else [()]:
        r = {**raw, "ego": dict(raw["ego"]), "actors": [dict(a) for a in actors]}
        for n, v in zip(names, combo):
            set_flat(r, n, v)
        try:
            case_name = template.format(**{n: fmt_value(v) for n, v in zip(names, combo)})
        except (KeyError, IndexError) as e:
            raise fail(
                src, "case_name", template, f"refers to {e} which is not a swept field (swept: {names})"
            ) from None
        except (ValueError, AttributeError) as e:
            raise fail(src, "case_name", template, f"is not a valid name template ({e})") from None
        cases.append(_resolve(r, case_name, src))
    seen = set()
    for c in cases:
        if c.name in seen:
            raise fail(src, "case_name", template, f"gives the name {c.name!r} to several cases")
        seen.add(c.name)
    return cases


def _resolve(r: dict, case_name: str, src: str) -> ScenarioCase:
    """One expanded case (no lists left) -> a validated ScenarioCase: the top-level fields,
    the road, the ego, then each actor with its lane change."""
    if not isinstance(r["threat"], bool):
        raise fail(src, "threat", r["threat"], "must be true or false")
    duration = number(src, "duration_s", r.get("duration_s", 12.0), 0.5, 120.0)
    road = _road(r.get("road") or {}, src)
    ego = EgoSpec(speed_kph=number(src, "ego.speed_kph", r["ego"].get("speed_kph", 50.0), 0.0, 200.0))
    actors = tuple(_actor(a, f"actors[{i}]", src, road, ego, duration) for i, a in enumerate(r["actors"]))
    traffic = integer(src, "traffic", r.get("traffic", 0), 0, 12)
    description = r.get("description", "")
    if not isinstance(description, str):
        raise fail(src, "description", description, "must be a string")
    return ScenarioCase(
        family=r["name"],
        name=case_name,
        description=description,
        threat=r["threat"],
        duration_s=duration,
        road=road,
        ego=ego,
        actors=actors,
        traffic=traffic,
        source=src,
    )


def _road(road_raw: dict, src: str) -> RoadConfig:
    check_keys(src, "road", road_raw, _ROAD_KEYS - _ROAD_COMPUTED)
    road_kw = {}
    for k, v in road_raw.items():
        default = _ROAD_DEFAULTS[k]
        if isinstance(default, bool):
            if not isinstance(v, bool):
                raise fail(src, f"road.{k}", v, "must be true or false")
            road_kw[k] = v
        elif isinstance(default, int):
            road_kw[k] = integer(src, f"road.{k}", v, 0, 6)
        else:
            road_kw[k] = number(src, f"road.{k}", v, 0.0, 1e4, lo_open=True)
    try:
        return RoadConfig(**road_kw)
    except ValueError as e:
        raise ConfigError(f"{src}: road: {e}") from None


def _actor(a: dict, k: str, src: str, road: RoadConfig, ego: EgoSpec, duration: float) -> ActorSpec:
    vehicle = a.get("vehicle", "car")
    if vehicle not in VEHICLE_CLASSES:
        raise fail(src, f"{k}.vehicle", vehicle, f"unknown vehicle (known: {', '.join(sorted(VEHICLE_CLASSES))})")
    lane = integer(src, f"{k}.lane", a.get("lane", 0), -road.lanes_right, road.lanes_left)
    direction = a.get("direction", "same")
    if direction not in ("same", "oncoming"):
        raise fail(src, f"{k}.direction", direction, "must be 'same' or 'oncoming'")
    hs, hm = a.get("headway_s"), a.get("headway_m")
    if (hs is None) == (hm is None):
        raise fail(src, f"{k}.headway_s/headway_m", (hs, hm), "give exactly one of them")
    if hs is not None:
        number(src, f"{k}.headway_s", hs, 0.0, 60.0, lo_open=True)
        if ego.speed_kph == 0:
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
    )


def _lane_change(lc_raw, k: str, src: str, road: RoadConfig, duration: float) -> LaneChange | None:
    if lc_raw is None:
        return None
    check_keys(src, f"{k}.lane_change", lc_raw, _LC_KEYS)
    for lk, lv in lc_raw.items():
        check_not_list(src, f"{k}.lane_change.{lk}", lv)
    return LaneChange(
        start_s=number(src, f"{k}.lane_change.start_s", lc_raw.get("start_s", 0.0), 0.0, duration),
        duration_s=number(src, f"{k}.lane_change.duration_s", lc_raw.get("duration_s", 2.0), 0.5, 10.0),
        to_lane=integer(src, f"{k}.lane_change.to_lane", lc_raw.get("to_lane", 0), -road.lanes_right, road.lanes_left),
    )


@dataclass
class Catalog:
    """Every case of every bundled scenario file, by family and by case name."""

    families: dict[str, list[ScenarioCase]] = field(default_factory=dict)

    @property
    def cases(self) -> dict[str, ScenarioCase]:
        return {c.name: c for cs in self.families.values() for c in cs}
