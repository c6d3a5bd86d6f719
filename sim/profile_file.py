"""Device profile files: what ``bittc profile --out FILE`` writes and ``--latency
profile:FILE`` reads. Pure Python (yaml, numpy), no network.

A profile file is one YAML mapping::

    name: my-laptop              # a label (the file is named by its path in outputs)
    bittc: {extract_ms: 4.1, view_ms: 1.9, threshold_ms: 2.3, job_ms: 0.4}   # cost terms [ms]
    flow: {extract_ms: 0.0, view_ms: 2.1, threshold_ms: 0.1, job_ms: 0.3}     # (sim.cost_model)
    continuous_ms: 76.0          # [ms] one continuous-TTC call of the network
    measured: true
    source: "..."                # how it was made, in words
    timings_ms: [{estimator: bittc, views: 1, thresholds: 4, extractions: 1, median_ms: 15.2}, ...]
    fit: {bittc: {rms_residual_ms: 0.4, max_residual_ms: 0.8}, flow: {...}}
    backend: torch               # torch | onnxruntime
    size_px: [96, 288]           # (H, W) of the timed frames
    threads: 2
    weights: {file: ..., sha256: ..., release: ...}
    machine: {platform: ..., processor: ..., cpus: ..., python: ...}
    versions: {bittc-sim: ..., torch: ..., onnxruntime: ..., numpy: ...}
    date: "2026-12-02"

Reading refuses unknown keys, a missing key, cost terms that are missing, negative or
not finite, and a file of the older ``a_ms`` / ``b_ms`` form; the error names the file
and the key.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import yaml

from sim.cost_model import COST_FAMILIES, COST_TERMS, CostTerms, DeviceProfile, JobWork, LatencyError, parse_costs

REQUIRED = ("name", "measured", "source", "timings_ms", "backend", "size_px", "threads", "date")
OPTIONAL = ("continuous_ms", "fit", "weights", "machine", "versions", *COST_FAMILIES)


def _number(path, key: str, v, *, positive: bool = False) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0 or (positive and v == 0):
        raise LatencyError(
            f"profile file {str(path)!r}: {key} = {v!r} must be a finite number {'> 0' if positive else '>= 0'}"
        )
    return float(v)


def read_profile_file(path: str | Path, name: str | None = None) -> DeviceProfile:
    """Load and validate ``path``; the profile is named ``name`` (default: the path as given)."""
    p = Path(path)
    if not p.is_file():
        raise LatencyError(f"profile file {str(path)!r}: no such file (`bittc profile` makes one)")
    try:
        raw = yaml.safe_load(p.read_text())
    except (yaml.YAMLError, UnicodeDecodeError) as e:
        raise LatencyError(f"profile file {str(path)!r}: not valid YAML ({e})") from None
    if not isinstance(raw, dict):
        raise LatencyError(f"profile file {str(path)!r}: expected a mapping of keys, got {type(raw).__name__}")
    if "a_ms" in raw or "b_ms" in raw:
        raise LatencyError(
            f"profile file {str(path)!r}: an older profile (L = a + b K, one estimator, one view); "
            "make it again with `bittc profile`"
        )
    unknown = sorted(set(map(str, raw)) - set(REQUIRED) - set(OPTIONAL))
    if unknown:
        raise LatencyError(
            f"profile file {str(path)!r}: unknown key(s) {unknown}; known: {sorted(REQUIRED + OPTIONAL)}"
        )
    missing = [k for k in REQUIRED if k not in raw]
    if missing:
        raise LatencyError(f"profile file {str(path)!r}: missing key(s) {missing}")
    costs = parse_costs(f"profile file {str(path)!r}", {k: raw[k] for k in COST_FAMILIES if k in raw})
    cont = None if raw.get("continuous_ms") is None else _number(path, "continuous_ms", raw["continuous_ms"])
    timings = raw["timings_ms"]
    if not isinstance(timings, list) or not timings:
        raise LatencyError(f"profile file {str(path)!r}: timings_ms must be a list of timed jobs, got {timings!r}")
    for i, row in enumerate(timings):
        if not isinstance(row, dict) or set(row) != {*_WORK_KEYS, "median_ms"}:
            raise LatencyError(
                f"profile file {str(path)!r}: timings_ms[{i}] needs exactly {[*_WORK_KEYS, 'median_ms']}, got {row!r}"
            )
        _number(path, f"timings_ms[{i}].median_ms", row["median_ms"], positive=True)
    if not isinstance(raw["measured"], bool):
        raise LatencyError(f"profile file {str(path)!r}: measured = {raw['measured']!r} must be true or false")
    return DeviceProfile(name or str(path), costs, str(raw["source"]), raw["measured"], cont)


_WORK_KEYS = ("estimator", "views", "thresholds", "extractions")


def fit_cost_terms(rows: list[tuple[JobWork, float]]) -> tuple[CostTerms, float, float]:
    """(work, median [ms]) of one estimator family -> (its cost terms by non-negative least
    squares, rms residual [ms], max |residual| [ms]). A term whose column is all zero (no
    extraction, say) is fitted as 0."""
    X = np.array([[w.extractions, w.views, w.thresholds, 1.0] for w, _ in rows], dtype=np.float64)
    y = np.array([t for _, t in rows], dtype=np.float64)
    # exact non-negative least squares on 4 terms: the best of the least-squares fits on every
    # subset of the terms whose coefficients all come out >= 0 (the empty subset fits 0)
    coef, best = np.zeros(4), float(y @ y)
    for mask in range(1, 16):
        cols = [j for j in range(4) if mask >> j & 1 and X[:, j].any()]
        if len(cols) != bin(mask).count("1"):
            continue
        sol, *_ = np.linalg.lstsq(X[:, cols], y, rcond=None)
        if (sol < 0).any():
            continue
        trial = np.zeros(4)
        trial[cols] = sol
        r = y - X @ trial
        if float(r @ r) < best - 1e-12:
            coef, best = trial, float(r @ r)
    res = y - X @ coef
    terms = CostTerms(**{k: round(float(v), 4) for k, v in zip(COST_TERMS, coef)})
    return terms, float(np.sqrt(np.mean(res**2))), float(np.abs(res).max())


def write_profile_file(path: str | Path, doc: dict) -> None:
    """Write ``doc`` atomically after checking that it reads back."""
    from bittc_core.atomic import write_text_atomic

    text = "# made by `bittc profile`; read by `--latency profile:FILE` (sim.profile_file)\n" + yaml.safe_dump(
        doc, sort_keys=False, width=100
    )
    parsed = yaml.safe_load(text)
    missing = [k for k in REQUIRED if k not in parsed]
    if missing or set(parsed) - set(REQUIRED) - set(OPTIONAL):
        raise ValueError(f"write_profile_file: a profile document needs exactly the keys {REQUIRED} (+ {OPTIONAL})")
    write_text_atomic(Path(path), text)
