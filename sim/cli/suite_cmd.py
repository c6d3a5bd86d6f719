"""`bittc suite`: every bundled scenario (or a chosen few) with one controller, as a table."""

from __future__ import annotations

import argparse

import scenarios
from sim.cli.common import add_seed_flag, check_seed, writable_dir
from sim.cli.loop_flags import add_controller_flags, controller_from_args
from sim.cli.run_cmd import add_camera_flags, add_realism_flag, camera_from_args, sensor_from_args, textures_from_args


def add_parser(sub) -> argparse.ArgumentParser:
    p = sub.add_parser(
        "suite",
        help="run the bundled scenario suite and print a summary table",
        description="Runs every case of the bundled scenarios (or --scenarios A,B,...) and writes "
        "DIR/summary.csv, DIR/summary.json and one folder per case.",
    )
    add_controller_flags(p, default="oracle")
    p.add_argument("--out", required=True, help="output directory")
    p.add_argument(
        "--scenarios",
        default=None,
        help="comma-separated suites (ncap, near, benign, vru, junction, benign-vru, all, demo), families or cases "
        "(default: all bundled)",
    )
    add_seed_flag(p, "scenery/appearance/traffic seed of every case")
    p.add_argument("--markdown", action="store_true", help="print the table as Markdown (as in the README)")
    p.add_argument("--video", action="store_true", help="also write camera.mp4 for every case")
    add_realism_flag(p)
    add_camera_flags(p)
    return p


def run(args) -> int:
    from sim.suite import format_table, run_cases

    check_seed(args.seed)
    camera = camera_from_args(args)
    textures = textures_from_args(args)
    if args.scenarios:
        cases = [c for name in args.scenarios.split(",") for c in scenarios.resolve_suite(name.strip())]
    else:
        cases = list(scenarios.bundled().cases.values())
    controller, latency = controller_from_args(args, camera)
    sensor = sensor_from_args(args)
    out = writable_dir(args.out)
    kw = {"textures": textures, "latency": latency, "sensor": sensor}
    summaries = run_cases(cases, controller, camera, args.seed, out, video=args.video, **kw)
    print(format_table(summaries, markdown=args.markdown))
    print(f"wrote {out}/summary.csv")
    return 0
