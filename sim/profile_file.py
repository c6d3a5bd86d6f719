"""Device profile files: what ``bittc profile --out FILE`` writes and ``--latency
profile:FILE`` reads. Pure Python (yaml), no network.

A profile file is one YAML mapping::

    name: my-laptop              # a label (the file is named by its path in outputs)
    a_ms: 7.8                    # [ms] L = a_ms + b_ms * K, least squares over timings_ms
    b_ms: 2.4                    # [ms] per threshold
    continuous_ms: 76.0          # [ms] one continuous-TTC call
    measured: true
    source: "..."                # how it was made, in words
    timings_ms: {binary: {1: 11.0, 2: 13.0, ...}, continuous: 76.0}   # medians [ms] per K
    fit: {rms_residual_ms: 0.4, max_residual_ms: 0.8}
    backend: torch               # torch | onnxruntime
    size_px: [96, 288]           # (H, W) of the timed frames
    threads: 2
    weights: {file: ..., sha256: ..., release: ...}
    machine: {platform: ..., processor: ..., cpus: ..., python: ...}
    versions: {bittc-sim: ..., torch: ..., onnxruntime: ..., numpy: ...}
    date: "2026-12-02"

Reading refuses unknown keys, a missing key, numbers that are negative or not finite,
and a file without at least two K timings; the error names the file and the key.
"""

from __future__ import annotations

import math
from pathlib import Path

import yaml

from sim.latency import DeviceProfile, LatencyError

REQUIRED = ("name", "a_ms", "b_ms", "measured", "source", "timings_ms", "backend", "size_px", "threads", "date")
OPTIONAL = ("continuous_ms", "fit", "weights", "machine", "versions")


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
    unknown = sorted(set(map(str, raw)) - set(REQUIRED) - set(OPTIONAL))
    if unknown:
        raise LatencyError(
            f"profile file {str(path)!r}: unknown key(s) {unknown}; known: {sorted(REQUIRED + OPTIONAL)}"
        )
    missing = [k for k in REQUIRED if k not in raw]
    if missing:
        raise LatencyError(f"profile file {str(path)!r}: missing key(s) {missing}")
    a, b = _number(path, "a_ms", raw["a_ms"]), _number(path, "b_ms", raw["b_ms"])
    cont = None if raw.get("continuous_ms") is None else _number(path, "continuous_ms", raw["continuous_ms"])
    timings = raw["timings_ms"]
    binary = timings.get("binary") if isinstance(timings, dict) else None
    if not isinstance(binary, dict) or len(binary) < 2:
        raise LatencyError(
            f"profile file {str(path)!r}: timings_ms.binary needs the timings of at least two K values, got {binary!r}"
        )
    for k, t in binary.items():
        if isinstance(k, bool) or not isinstance(k, int) or k < 1:
            raise LatencyError(
                f"profile file {str(path)!r}: timings_ms.binary has K = {k!r}; K must be an integer >= 1"
            )
        _number(path, f"timings_ms.binary[{k}]", t, positive=True)
    if not isinstance(raw["measured"], bool):
        raise LatencyError(f"profile file {str(path)!r}: measured = {raw['measured']!r} must be true or false")
    return DeviceProfile(name or str(path), a, b, str(raw["source"]), raw["measured"], cont)


def fit_latency(binary_ms: dict[int, float]) -> tuple[float, float, float, float]:
    """K -> median [ms] -> (a_ms, b_ms, rms residual, max |residual|) of L = a + b K (least
    squares; a and b clipped at 0: a latency is never negative)."""
    ks = sorted(binary_ms)
    n = len(ks)
    mk, mt = sum(ks) / n, sum(binary_ms[k] for k in ks) / n
    var = sum((k - mk) ** 2 for k in ks)
    b = max(sum((k - mk) * (binary_ms[k] - mt) for k in ks) / var, 0.0)
    a = max(mt - b * mk, 0.0)
    res = [binary_ms[k] - (a + b * k) for k in ks]
    return a, b, math.sqrt(sum(r * r for r in res) / n), max(abs(r) for r in res)


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
