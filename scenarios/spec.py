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
from scenarios.checks import check_keys, check_name, check_unswept, fail, integer, number
from scenarios.paths import TURNS, ego_path, path_leaves_road
from scenarios.protocols import PROTOCOLS
from scenarios.road import RoadConfig
from scenarios.sweep_fields import flatten_sweeps, fmt_value, set_flat
from scenarios.vehicle_spec import ACTOR_KEYS, ActorSpec, LaneChange, vehicle_actor
from scenarios.vru_spec import VRU_KEYS, VruActorSpec, check_placement, is_vru_entry, vru_actor, vru_placement

__all__ = ["ActorSpec", "EgoSpec", "LaneChange", "ScenarioCase", "VruActorSpec", "expand", "load_file"]


#: default turn radius [m] of the ego's path at a junction, per turn (a left turn sweeps wider)
DEFAULT_TURN_RADIUS_M = {"left": 12.0, "right": 7.0, "straight": 12.0}


@dataclass(frozen=True)
class EgoSpec:
    speed_kph: float = 50.0
    turn: str = "straight"  # straight | left | right (at road.junction_m)
    turn_radius_m: float | None = None  # [m] None: DEFAULT_TURN_RADIUS_M
    conflict_s: float = 4.0  # [s] when its front would reach a crossing road user's line without braking

    @property
    def radius_m(self) -> float:
        return self.turn_radius_m if self.turn_radius_m is not None else DEFAULT_TURN_RADIUS_M[self.turn]


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
    actors: tuple[ActorSpec | VruActorSpec, ...]
    traffic: int = 0
    source: str = ""
    protocol: str = ""  # the test protocol (and version) the family follows, see scenarios.protocols

    @property
    def path(self):
        """The ego's nominal path (``scenarios.paths.EgoPath``)."""
        return ego_path(self.ego.turn, self.road, self.ego.radius_m)

    @property
    def vrus(self) -> tuple[VruActorSpec, ...]:
        return tuple(a for a in self.actors if isinstance(a, VruActorSpec))

    @property
    def open_paths(self) -> bool:
        """True when in-path decisions need the actors' future paths: road users, a
        junction, a turning ego or a car timed to meet the ego's path."""
        return bool(
            self.vrus
            or self.road.junction_m is not None
            or any(getattr(a, "offset_s", None) is not None for a in self.actors)
        )

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["actors"] = [asdict(a) for a in self.actors]
        return d


_TOP_KEYS = {"name", "description", "threat", "case_name", "duration_s", "road", "ego", "actors", "traffic", "protocol"}
_ROAD_KEYS = {f.name for f in fields(RoadConfig)}
_ROAD_COMPUTED = {"x_start_m", "x_end_m", "markings_max_x_m"}  # set by the simulator from the scenario
_ROAD_DEFAULTS = {f.name: f.default for f in fields(RoadConfig)}
_EGO_KEYS = {f.name for f in fields(EgoSpec)}


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
        check_keys(src, f"actors[{i}]", a, VRU_KEYS if is_vru_entry(a) else ACTOR_KEYS)
    protocol = raw.get("protocol", "")
    if protocol and protocol not in PROTOCOLS:
        raise fail(src, "protocol", protocol, f"unknown protocol (known: {', '.join(sorted(PROTOCOLS))})")
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
    ego = _ego(r["ego"], src, road, duration)
    heights = [
        float(a.get("height_m", 1.8)) for a in r["actors"] if isinstance(a, dict) and a.get("pedestrian") == "adult"
    ]
    actors = []
    for i, a in enumerate(r["actors"]):
        k = f"actors[{i}]"
        if is_vru_entry(a):
            vru = vru_actor(a, k, src, heights)
            if vru.crossing and ego.turn != "straight":
                raise fail(src, "ego.turn", ego.turn, "a crossing road user needs a straight ego path")
            check_placement(
                vru, vru_placement(vru, ego.speed_kph / 3.6, ego.conflict_s), k, src, road, duration, ego.conflict_s
            )
            actors.append(vru)
        else:
            actors.append(vehicle_actor(a, k, src, road, ego.speed_kph, duration))
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
        actors=tuple(actors),
        traffic=traffic,
        source=src,
        protocol=r.get("protocol", ""),
    )


def _ego(e: dict, src: str, road: RoadConfig, duration: float) -> EgoSpec:
    speed = number(src, "ego.speed_kph", e.get("speed_kph", 50.0), 0.0, 200.0)
    turn = e.get("turn", "straight")
    if turn not in TURNS:
        raise fail(src, "ego.turn", turn, f"must be one of {', '.join(TURNS)}")
    if turn != "straight" and road.junction_m is None:
        raise fail(src, "ego.turn", turn, "the turn leaves the road network: set road.junction_m")
    radius = e.get("turn_radius_m")
    if radius is not None:
        radius = number(src, "ego.turn_radius_m", radius, 4.0, 60.0)
    ego = EgoSpec(speed, turn, radius, number(src, "ego.conflict_s", e.get("conflict_s", 4.0), 1.0, 30.0))
    if turn != "straight":
        path = ego_path(turn, road, ego.radius_m)
        if path.turn_start_s < 0:
            raise fail(src, "road.junction_m", road.junction_m, f"the {turn} turn would start behind the ego")
        off = path_leaves_road(path, road, speed / 3.6 * duration + 20.0)
        if off is not None:
            raise fail(
                src,
                "ego.turn_radius_m",
                ego.radius_m,
                f"the ego's path leaves the road network at ({off[0]:.1f}, {off[1]:.1f}) m",
            )
    return ego


def _road(road_raw: dict, src: str) -> RoadConfig:
    check_keys(src, "road", road_raw, _ROAD_KEYS - _ROAD_COMPUTED)
    road_kw = {}
    for k, v in road_raw.items():
        if k == "junction_m":
            road_kw[k] = number(src, "road.junction_m", v, 20.0, 1e4)
            continue
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


@dataclass
class Catalog:
    """Every case of every bundled scenario file, by family and by case name."""

    families: dict[str, list[ScenarioCase]] = field(default_factory=dict)

    @property
    def cases(self) -> dict[str, ScenarioCase]:
        return {c.name: c for cs in self.families.values() for c in cs}
