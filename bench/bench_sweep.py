"""Sweep throughput, measured in one run: runs per minute with 1 and 2 local workers (and
Ray with 2 when it is installed), on the same sweep with fixed latency, so that the
runs are the same and ``results.csv`` must come out byte-identical (checked, printed).

Usage: python bench/bench_sweep.py [--suite demo] [--num-alphas 1 4 16] [--latency fixed:50]
Prints runs/min of each and the ratio to 1 worker. Wall time includes each backend's
start-up (process spawn, imports, Ray's start), as a user's sweep pays it. Nothing is
asserted; run it on an otherwise idle machine.
"""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

from sim.sweep.plan import SweepSettings  # noqa: E402
from sim.sweep.sweep import run_sweep  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--suite", nargs="+", default=["demo"])
    ap.add_argument("--controllers", nargs="+", default=["geofence", "oracle"])
    ap.add_argument("--num-alphas", type=int, nargs="+", default=[1, 4, 16])
    ap.add_argument("--latency", nargs="+", default=["fixed:50"])
    args = ap.parse_args()
    settings = SweepSettings(
        suites=tuple(args.suite),
        controllers=tuple(args.controllers),
        num_alphas=tuple(args.num_alphas),
        latencies=tuple(args.latency),
    )
    setups = [("local", 1), ("local", 2)]
    try:
        import ray  # noqa: F401

        setups.append(("ray", 2))
    except ImportError:
        pass
    rates, results = {}, {}
    with tempfile.TemporaryDirectory() as d:
        for backend, workers in setups:
            out = Path(d) / f"{backend}{workers}"
            o = run_sweep(settings, out, workers=workers, backend=backend, progress=False)
            rates[(backend, workers)] = o.runs_per_min
            results[(backend, workers)] = (out / "results.csv").read_bytes()
            print(f"{backend:>5} x {workers}: {o.runs} runs in {o.seconds:.1f} s = {o.runs_per_min:.1f} runs/min")
    base = rates[("local", 1)]
    for key, r in rates.items():
        same = results[key] == results[("local", 1)]
        print(
            f"{key[0]:>5} x {key[1]}: {r / base:.2f}x the 1-worker rate; results.csv "
            f"{'identical' if same else 'DIFFERS'}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
