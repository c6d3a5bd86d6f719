"""Sweep fields of scenario files: a list in a field of ``ego`` or of an actor is a sweep
over its values; flat names (``ego_speed_kph``, ``actor0_overlap_pct``) name them in
``case_name`` templates."""

from __future__ import annotations

from typing import Any


def flatten_sweeps(raw: dict) -> tuple[list[str], list[list[Any]]]:
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


def set_flat(raw: dict, name: str, value: Any) -> None:
    if name.startswith("ego_"):
        raw["ego"][name[4:]] = value
    else:
        idx, key = name[5:].split("_", 1)
        raw["actors"][int(idx)][key] = value


def fmt_value(v: Any) -> str:
    if isinstance(v, float) and v.is_integer():
        return str(int(v))
    return str(v)
