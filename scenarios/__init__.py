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


__all__ = ["ScenarioCase", "bundled", "resolve", "load_file"]
