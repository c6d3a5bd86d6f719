"""Small builders shared by the simulator tests."""

from __future__ import annotations

from scenarios.spec import expand


def case(ego_kph: float, actors: list[dict], threat: bool = True, duration_s: float = 10.0, **top):
    raw = {
        "name": "t",
        "threat": threat,
        "duration_s": duration_s,
        "ego": {"speed_kph": ego_kph},
        "actors": actors,
        **top,
    }
    return expand(raw, "<test>")[0]
