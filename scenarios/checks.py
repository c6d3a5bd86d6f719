"""Value checks of scenario files: each failure a ConfigError naming the file, key and value."""

from __future__ import annotations

import math
from typing import Any

from bittc_core.errors import ConfigError


def fail(src: str, key: str, value: Any, why: str) -> ConfigError:
    return ConfigError(f"{src}: {key} = {value!r}: {why}")


def check_not_list(src: str, key: str, v: Any) -> None:
    if isinstance(v, list):
        raise fail(src, key, v, "a list expands into a sweep only in the fields of ego and of each actor")


def check_unswept(src: str, raw: dict) -> None:
    """No list outside the fields of ``ego`` and of each actor (where lists are sweeps)."""
    for k, v in raw.items():
        if k not in ("ego", "actors"):
            check_not_list(src, k, v)
    if isinstance(raw.get("road"), dict):
        for k, v in raw["road"].items():
            check_not_list(src, f"road.{k}", v)


def check_name(src: str, key: str, v: Any, template: bool = False) -> str:
    """A family name (no spaces) or a ``case_name`` template: a non-empty string."""
    if not isinstance(v, str) or not v or (not template and any(ch.isspace() for ch in v)):
        raise fail(src, key, v, "must be a non-empty string" + ("" if template else " without spaces"))
    return v


def check_keys(src: str, where: str, d: Any, allowed: set[str]) -> None:
    if not isinstance(d, dict):
        raise fail(src, where, d, "must be a mapping")
    unknown = sorted(set(d) - allowed)
    if unknown:
        raise fail(
            src,
            f"{where}.{unknown[0]}" if where else unknown[0],
            d[unknown[0]],
            f"unknown key (allowed: {', '.join(sorted(allowed))})",
        )


def number(
    src: str, key: str, v: Any, lo: float | None = None, hi: float | None = None, lo_open: bool = False
) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise fail(src, key, v, "must be a finite number")
    if lo is not None and (v < lo or (lo_open and v == lo)):
        raise fail(src, key, v, f"must be {'>' if lo_open else '>='} {lo}")
    if hi is not None and v > hi:
        raise fail(src, key, v, f"must be <= {hi}")
    return float(v)


def integer(src: str, key: str, v: Any, lo: int, hi: int) -> int:
    if isinstance(v, bool) or not isinstance(v, int):
        raise fail(src, key, v, "must be an integer")
    if not lo <= v <= hi:
        raise fail(src, key, v, f"must be in [{lo}, {hi}]")
    return v
