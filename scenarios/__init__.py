"""Bundled scenario files and name resolution.

``resolve("CCRs-50")`` returns one case, ``resolve("CCRs")`` every case of the family,
``resolve("path/to/file.yaml")`` every case of that file.
"""

from __future__ import annotations

import difflib
from functools import lru_cache
from pathlib import Path

from bittc_core.errors import ConfigError
from scenarios.spec import Catalog, ScenarioCase, load_file

BUNDLED_DIR = Path(__file__).resolve().parent


@lru_cache(maxsize=1)
def bundled() -> Catalog:
    cat = Catalog()
    for path in sorted(BUNDLED_DIR.glob("*.yaml")):
        cases = load_file(path)
        family = cases[0].family
        if family in cat.families:
            raise ConfigError(f"{path}: family name {family!r} is used by two bundled files")
        cat.families[family] = cases
    return cat


#: named sets of bundled families (``bittc scenarios --suites``); a suite resolves to every case of them
SUITES: dict[str, str] = {
    "ncap": "every Euro NCAP car-to-car case: CCRs, CCRs-offset, CCRm, CCRb",
    "benign": "every benign scenario on the straight road with vehicles only (no warning or brake expected)",
    "near": "actors entering the ego's lane close ahead: a slow van merging 15-25 m ahead, close cut-ins, "
    "a GVT at +-75 % overlap (what the wide view is for)",
    "vru": "every Euro NCAP pedestrian and cyclist case: CPFA, CPNA, CPNCO, CPLA, CBNA, CBNAO, CBFA, CBLA",
    "junction": "every Euro NCAP junction and crossing-traffic case: CCFtap, CCCscp, CCFhos",
    "benign-vru": "the benign counterparts of the road-user and junction cases (no warning or brake expected)",
    "all": "every bundled case",
    "demo": "four cases that show the trade-off: CCRs-50 (K decides), benign-oncoming (no false alarm), "
    "CPLA-25-40 (a pedestrian walking ahead in the path), CCFtap-20-45 (turning across an oncoming car at a junction)",
}
NCAP_FAMILIES = ("CCRs", "CCRs-offset", "CCRm", "CCRb")
NEAR_FAMILIES = ("near-merge", "near-cut-in", "near-gvt-offset")
VRU_FAMILIES = ("CPFA", "CPNA", "CPNCO", "CPLA", "CBNA", "CBNAO", "CBFA", "CBLA")
JUNCTION_FAMILIES = ("CCFtap", "CCCscp", "CCFhos")
DEMO_CASES = ("CCRs-50", "benign-oncoming", "CPLA-25-40", "CCFtap-20-45")


def resolve_suite(name: str) -> list[ScenarioCase]:
    """The cases of a suite (``SUITES``), or of a bundled name or YAML file (``resolve``)."""
    cat = bundled()
    if name == "ncap":
        return [c for f in NCAP_FAMILIES for c in cat.families[f]]
    if name == "benign":
        return [c for cases in cat.families.values() for c in cases if not c.threat and not c.open_paths]
    if name == "benign-vru":
        return [c for cases in cat.families.values() for c in cases if not c.threat and c.open_paths]
    if name == "vru":
        return [c for f in VRU_FAMILIES for c in cat.families[f]]
    if name == "junction":
        return [c for f in JUNCTION_FAMILIES for c in cat.families[f]]
    if name == "near":
        return [c for f in NEAR_FAMILIES for c in cat.families[f]]
    if name == "all":
        return list(cat.cases.values())
    if name == "demo":
        return [cat.cases[n] for n in DEMO_CASES]
    return resolve(name)


def resolve(name_or_path: str) -> list[ScenarioCase]:
    """Cases for a bundled family, a bundled case, or a YAML file path."""
    if name_or_path.endswith((".yaml", ".yml")) or "/" in name_or_path:
        return load_file(name_or_path)
    cat = bundled()
    if name_or_path in cat.families:
        return list(cat.families[name_or_path])
    cases = cat.cases
    if name_or_path in cases:
        return [cases[name_or_path]]
    known = list(cat.families) + list(cases)
    close = difflib.get_close_matches(name_or_path, known, n=3, cutoff=0.5)
    hint = f"; did you mean {', '.join(close)}?" if close else "; `bittc scenarios` lists them"
    raise ConfigError(f"unknown scenario {name_or_path!r}{hint}")


__all__ = ["ScenarioCase", "SUITES", "bundled", "resolve", "resolve_suite", "load_file"]
