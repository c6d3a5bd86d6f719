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
import math
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import Any

import yaml

from bittc_core.errors import ConfigError
from scenarios.road import RoadConfig
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


def _fail(src: str, key: str, value: Any, why: str) -> ConfigError:
    return ConfigError(f"{src}: {key} = {value!r}: {why}")


def _check_not_list(src: str, key: str, v: Any) -> None:
    if isinstance(v, list):
        raise _fail(src, key, v, "a list expands into a sweep only in the fields of ego and of each actor")


def _check_unswept(src: str, raw: dict) -> None:
    """No list outside the fields of ``ego`` and of each actor (where lists are sweeps)."""
    for k, v in raw.items():
        if k not in ("ego", "actors"):
            _check_not_list(src, k, v)
    if isinstance(raw.get("road"), dict):
        for k, v in raw["road"].items():
            _check_not_list(src, f"road.{k}", v)


def _check_name(src: str, key: str, v: Any, template: bool = False) -> str:
    """A family name (no spaces) or a ``case_name`` template: a non-empty string."""
    if not isinstance(v, str) or not v or (not template and any(ch.isspace() for ch in v)):
        raise _fail(src, key, v, "must be a non-empty string" + ("" if template else " without spaces"))
    return v


def _check_keys(src: str, where: str, d: Any, allowed: set[str]) -> None:
    if not isinstance(d, dict):
        raise _fail(src, where, d, "must be a mapping")
    unknown = sorted(set(d) - allowed)
    if unknown:
        raise _fail(src, f"{where}.{unknown[0]}" if where else unknown[0], d[unknown[0]], f"unknown key (allowed: {', '.join(sorted(allowed))})")


def _number(src: str, key: str, v: Any, lo: float | None = None, hi: float | None = None, lo_open: bool = False) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise _fail(src, key, v, "must be a finite number")
    if lo is not None and (v < lo or (lo_open and v == lo)):
        raise _fail(src, key, v, f"must be {'>' if lo_open else '>='} {lo}")
    if hi is not None and v > hi:
        raise _fail(src, key, v, f"must be <= {hi}")
    return float(v)


def _int(src: str, key: str, v: Any, lo: int, hi: int) -> int:
    if isinstance(v, bool) or not isinstance(v, int):
        raise _fail(src, key, v, "must be an integer")
    if not lo <= v <= hi:
        raise _fail(src, key, v, f"must be in [{lo}, {hi}]")
    return v


def _flatten_sweeps(raw: dict) -> tuple[list[str], list[list[Any]]]:
    """Paths (flat names) and value lists of every list-valued scalar field."""
    names, values = [], []
    for k, v in raw.get("ego", {}).items() if isinstance(raw.get("ego"), dict) else []:
        if isinstance(v, list):
            names.append(f"ego_{k}")
            values.append(v)
    for i, a in enumerate(raw.get("actors", []) or []):
        if isinstance(a, dict):
            for k, v in a.items():
                if isinstance(v, list):
                    names.append(f"actor{i}_{k}")
                    values.append(v)
    return names, values


def _set_flat(raw: dict, name: str, value: Any) -> None:
    if name.startswith("ego_"):
        raw["ego"][name[4:]] = value
    else:
        idx, key = name[5:].split("_", 1)
        raw["actors"][int(idx)][key] = value


def _fmt(v: Any) -> str:
    if isinstance(v, float) and v.is_integer():
        return str(int(v))
    return str(v)


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
    _check_keys(src, "", raw, _TOP_KEYS)
    for req in ("name", "threat", "ego"):
        if req not in raw:
            raise ConfigError(f"{src}: missing required key {req!r}")
    _check_unswept(src, raw)
    _check_name(src, "name", raw["name"])
    _check_keys(src, "ego", raw["ego"], _EGO_KEYS)
    actors = raw.get("actors") or []
    if not isinstance(actors, list):
        raise _fail(src, "actors", actors, "must be a list")
    for i, a in enumerate(actors):
        _check_keys(src, f"actors[{i}]", a, _ACTOR_KEYS)
    names, values = _flatten_sweeps(raw)
    for n, vs in zip(names, values):
        if len(vs) == 0:
            raise _fail(src, n, vs, "an empty list expands to no run")
    template = raw.get("case_name")
    if template is None:
        template = raw["name"] + "".join(f"-{{{n}}}" for n in names)
    _check_name(src, "case_name", template, template=True)
    cases = []
    for combo in itertools.product(*values) if names else [()]:
        r = {**raw, "ego": dict(raw["ego"]), "actors": [dict(a) for a in actors]}
        for n, v in zip(names, combo):
            _set_flat(r, n, v)
        try:
            case_name = template.format(**{n: _fmt(v) for n, v in zip(names, combo)})
        except (KeyError, IndexError) as e:
            raise _fail(src, "case_name", template, f"refers to {e} which is not a swept field (swept: {names})") from None
        except (ValueError, AttributeError) as e:
            raise _fail(src, "case_name", template, f"is not a valid name template ({e})") from None
        cases.append(_resolve(r, case_name, src))
    seen = set()
    for c in cases:
        if c.name in seen:
            raise _fail(src, "case_name", template, f"gives the name {c.name!r} to several cases")
        seen.add(c.name)
    return cases


def _resolve(r: dict, case_name: str, src: str) -> ScenarioCase:
    name = r["name"]
    if not isinstance(r["threat"], bool):
        raise _fail(src, "threat", r["threat"], "must be true or false")
    duration = _number(src, "duration_s", r.get("duration_s", 12.0), 0.5, 120.0)
    road_raw = r.get("road") or {}
    _check_keys(src, "road", road_raw, _ROAD_KEYS - _ROAD_COMPUTED)
    road_kw = {}
    for k, v in road_raw.items():
        default = _ROAD_DEFAULTS[k]
        if isinstance(default, bool):
            if not isinstance(v, bool):
                raise _fail(src, f"road.{k}", v, "must be true or false")
            road_kw[k] = v
        elif isinstance(default, int):
            road_kw[k] = _int(src, f"road.{k}", v, 0, 6)
        else:
            road_kw[k] = _number(src, f"road.{k}", v, 0.0, 1e4, lo_open=True)
    try:
        road = RoadConfig(**road_kw)
    except ValueError as e:
        raise ConfigError(f"{src}: road: {e}") from None
    ego = EgoSpec(speed_kph=_number(src, "ego.speed_kph", r["ego"].get("speed_kph", 50.0), 0.0, 200.0))
    actors = []
    for i, a in enumerate(r["actors"]):
        k = f"actors[{i}]"
        vehicle = a.get("vehicle", "car")
        if vehicle not in VEHICLE_CLASSES:
            raise _fail(src, f"{k}.vehicle", vehicle, f"unknown vehicle (known: {', '.join(sorted(VEHICLE_CLASSES))})")
        lane = _int(src, f"{k}.lane", a.get("lane", 0), -road.lanes_right, road.lanes_left)
        direction = a.get("direction", "same")
        if direction not in ("same", "oncoming"):
            raise _fail(src, f"{k}.direction", direction, "must be 'same' or 'oncoming'")
        hs, hm = a.get("headway_s"), a.get("headway_m")
        if (hs is None) == (hm is None):
            raise _fail(src, f"{k}.headway_s/headway_m", (hs, hm), "give exactly one of them")
        if hs is not None:
            _number(src, f"{k}.headway_s", hs, 0.0, 60.0, lo_open=True)
            if ego.speed_kph == 0:
                raise _fail(src, f"{k}.headway_s", hs, "a time headway needs a moving ego (use headway_m)")
        if hm is not None:
            _number(src, f"{k}.headway_m", hm, 0.0, 500.0, lo_open=True)
        decel = _number(src, f"{k}.decel_mps2", a.get("decel_mps2", 0.0), 0.0, 12.0)
        accel = _number(src, f"{k}.accel_mps2", a.get("accel_mps2", 0.0), 0.0, 6.0)
        if decel > 0 and accel > 0:
            raise _fail(src, f"{k}.accel_mps2", accel, "cannot be combined with decel_mps2")
        lc_raw = a.get("lane_change")
        lc = None
        if lc_raw is not None:
            _check_keys(src, f"{k}.lane_change", lc_raw, _LC_KEYS)
            for lk, lv in lc_raw.items():
                _check_not_list(src, f"{k}.lane_change.{lk}", lv)
            lc = LaneChange(
                start_s=_number(src, f"{k}.lane_change.start_s", lc_raw.get("start_s", 0.0), 0.0, duration),
                duration_s=_number(src, f"{k}.lane_change.duration_s", lc_raw.get("duration_s", 2.0), 0.5, 10.0),
                to_lane=_int(src, f"{k}.lane_change.to_lane", lc_raw.get("to_lane", 0), -road.lanes_right, road.lanes_left),
            )
        actors.append(
            ActorSpec(
                vehicle=vehicle, lane=lane, direction=direction,
                speed_kph=_number(src, f"{k}.speed_kph", a.get("speed_kph", 0.0), 0.0, 200.0),
                overlap_pct=_number(src, f"{k}.overlap_pct", a.get("overlap_pct", 100.0), -100.0, 100.0),
                headway_s=None if hs is None else float(hs), headway_m=None if hm is None else float(hm),
                decel_mps2=decel, brake_onset_s=_number(src, f"{k}.brake_onset_s", a.get("brake_onset_s", 0.0), 0.0, duration),
                accel_mps2=accel, lane_change=lc,
            )
        )  # fmt: skip
    traffic = _int(src, "traffic", r.get("traffic", 0), 0, 12)
    description = r.get("description", "")
    if not isinstance(description, str):
        raise _fail(src, "description", description, "must be a string")
    return ScenarioCase(family=name, name=case_name, description=description, threat=r["threat"], duration_s=duration,
                        road=road, ego=ego, actors=tuple(actors), traffic=traffic, source=src)  # fmt: skip


@dataclass
class Catalog:
    """Every case of every bundled scenario file, by family and by case name."""

    families: dict[str, list[ScenarioCase]] = field(default_factory=dict)

    @property
    def cases(self) -> dict[str, ScenarioCase]:
        return {c.name: c for cs in self.families.values() for c in cs}
