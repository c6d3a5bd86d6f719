"""`bittc demo`: the network braking on the demo suite, with the oracle beside it, as a report."""

from __future__ import annotations

import argparse
import os
import shlex
import sys
import time

DEMO_NUM_ALPHAS = (1, 4, 16)
DEMO_FOVEAS = ("off", "4")  # the wide view alone beside wide + fovea x4
DEMO_VIDEO_CASE = "CCRs-50"  # where K decides the outcome: the first brake comes later with fewer fences
# the latency every run is charged: this CPU's measured cost terms (sim/device_profiles/this-cpu.yaml),
# so that the two workers' runs do not slow each other's estimators and every demo gives the same bytes
DEMO_LATENCY = "profile:this-cpu"
DEMO_WORKERS = 2  # both cores of a 2-core laptop


def add_parser(sub) -> argparse.ArgumentParser:
    p = sub.add_parser(
        "demo",
        help="the shipped network at K = 1, 4, 16 with and without a fovea, and the oracle, as a report",
        description="Runs the demo suite (`bittc scenarios --suites`) with the geofence controller "
        "(shipped weights) at K = 1, 4 and 16, with the wide view alone and with a fovea, and the oracle, "
        f"on {DEMO_WORKERS} worker processes, each job's latency charged as this CPU's profile prices it "
        f"({DEMO_LATENCY}: the same bytes on every run), writes a video of "
        f"{DEMO_VIDEO_CASE} and an HTML report, and prints where the report is.",
    )
    p.add_argument("--out", default="runs/demo", help="output directory (default runs/demo; must be new or a demo)")
    p.add_argument(
        "--fovea",
        nargs="+",
        default=list(DEMO_FOVEAS),
        metavar="ZOOM|off",
        help=f"fovea settings to compare (default {' '.join(DEMO_FOVEAS)}: the wide view alone and with a fovea)",
    )
    return p


def run(args) -> int:
    from sim.cli.common import parse_fovea
    from sim.cli.sweep_cmd import execute
    from sim.sweep.plan import SweepSettings

    foveas = tuple(dict.fromkeys(parse_fovea(f) for f in args.fovea))
    settings = SweepSettings(
        suites=("demo",),
        controllers=("geofence", "oracle"),
        num_alphas=DEMO_NUM_ALPHAS,
        latencies=(DEMO_LATENCY,),
        seeds=1,
        video_cases=(DEMO_VIDEO_CASE,),
        timeline_case=DEMO_VIDEO_CASE,
        foveas=foveas,
    )
    workers = max(1, min(DEMO_WORKERS, os.cpu_count() or 1))
    args.workers, args.backend, args.ray_address, args.resume = workers, "local", None, True
    t0 = time.perf_counter()
    rc = execute(settings, args, "bittc demo " + shlex.join(sys.argv[2:]))
    print(f"demo finished in {time.perf_counter() - t0:.0f} s; open the report in a browser")
    return rc
