"""`bittc sweep`: suites x controllers x K x latency modes x seeds, with a table, plots
and an HTML report."""

from __future__ import annotations

import argparse
import shlex
import sys

from bittc_core.errors import CliError, ConfigError
from sim.cli.common import add_fovea_flag, flag_error, parse_fovea


def add_parser(sub) -> argparse.ArgumentParser:
    p = sub.add_parser(
        "sweep",
        help="run a suite over controllers, K and latency modes; table, plots, report",
        description="Runs every case of the suites with every controller, K and latency mode, then "
        "writes DIR/results.csv (one row per run), DIR/summary.{md,csv} (per controller x K x "
        "latency), DIR/plots/*.png and DIR/report.html.",
    )
    p.add_argument(
        "--suite",
        nargs="+",
        required=True,
        metavar="NAME",
        help="suites (`bittc scenarios --suites`: ncap, near, benign, vru, junction, benign-vru, all, demo), "
        "bundled names or YAML files",
    )
    p.add_argument(
        "--controllers",
        nargs="+",
        default=["geofence", "oracle"],
        metavar="NAME",
        help="registered controllers (geofence, flow, geofence-exact, oracle, none) or module:Class (default geofence "
        "oracle)",
    )
    p.add_argument(
        "--num-alphas",
        type=int,
        nargs="+",
        default=[1, 2, 4, 8, 16],
        metavar="K",
        help="threshold counts for geofence/flow (default 1 2 4 8 16)",
    )
    p.add_argument(
        "--latency",
        nargs="+",
        default=["measured"],
        metavar="MODE",
        help="latency modes: measured, fixed:MS, profile:NAME, profile:FILE (default measured)",
    )
    add_fovea_flag(p, many=True)
    p.add_argument("--seeds", type=int, default=1, help="seeds 0..N-1 per run (default 1)")
    p.add_argument("--out", required=True, help="output directory (new, or this sweep's with --resume)")
    p.add_argument(
        "--workers", type=int, default=1, help="parallel runs (default 1; see the report on measured latency)"
    )
    p.add_argument(
        "--backend", choices=("local", "ray"), default="local", help="local processes or Ray (default local)"
    )
    p.add_argument(
        "--ray-address", default=None, help="with --backend ray: the cluster's address (default: a local Ray)"
    )
    p.add_argument("--resume", action="store_true", help="continue the sweep in --out, skipping finished runs")
    p.add_argument("--weights", default=None, help="geofence: network weights (default: the shipped ones)")
    p.add_argument(
        "--frame-stride", type=int, default=None, metavar="N", help="geofence/flow: frame stride (default 3)"
    )
    p.add_argument("--video", nargs="+", default=[], metavar="CASE", help="also write camera.mp4 for these cases' runs")
    p.add_argument(
        "--timeline-case",
        default=None,
        metavar="CASE",
        help="the case of the timeline plot (default: the first threat case)",
    )
    p.add_argument(
        "--net-backend",
        default="torch",
        choices=("torch", "onnxruntime"),
        help="geofence: the network on torch (default) or onnxruntime (needs --onnx DIR)",
    )
    p.add_argument(
        "--onnx", default=None, metavar="DIR", help="with --net-backend onnxruntime: `bittc export --onnx DIR`"
    )
    return p


_FLAGS = {
    "suites": "--suite",
    "controllers": "--controllers",
    "num_alphas": "--num-alphas",
    "latencies": "--latency",
    "seeds": "--seeds",
    "weights": "--weights",
    "frame_stride": "--frame-stride",
    "video_cases": "--video",
    "timeline_case": "--timeline-case",
    "workers": "--workers",
    "net_backend": "--net-backend",
    "onnx": "--onnx",
    "foveas": "--fovea",
}


def settings_from_args(args):
    from sim.sweep.plan import SweepSettings

    return SweepSettings(
        suites=tuple(args.suite),
        controllers=tuple(args.controllers),
        num_alphas=tuple(args.num_alphas),
        latencies=tuple(args.latency),
        seeds=args.seeds,
        weights=args.weights,
        frame_stride=args.frame_stride,
        video_cases=tuple(args.video),
        timeline_case=args.timeline_case,
        net_backend=args.net_backend,
        onnx=args.onnx,
        foveas=tuple(dict.fromkeys(parse_fovea(f) for f in args.fovea)),
    )


def execute(settings, args, command: str) -> int:
    from sim.sweep.sweep import run_sweep

    try:
        outcome = run_sweep(
            settings,
            _out(args.out),
            workers=args.workers,
            backend=args.backend,
            ray_address=args.ray_address,
            resume=args.resume,
            command=command,
        )
    except ConfigError as e:
        raise flag_error(e, _FLAGS) from None
    print(outcome.summary_md)
    rate = f", {outcome.runs_per_min:.1f} runs/min" if outcome.runs_per_min else ""
    print(
        f"{outcome.runs} runs ({outcome.executed} executed in {outcome.seconds:.0f} s on {args.workers} "
        f"{args.backend} worker(s){rate})"
    )
    print(f"report: {outcome.report}")
    if outcome.failed:
        print(f"{len(outcome.failed)} run(s) failed (errors in {outcome.out / 'failures.json'}):", file=sys.stderr)
        for run_id in outcome.failed:
            print(f"  {run_id}", file=sys.stderr)
        return 1
    return 0


def _out(path: str):
    from pathlib import Path

    p = Path(path)
    if p.exists() and not p.is_dir():
        raise CliError(f"--out {path!r}: exists and is not a directory")
    return p


def run(args) -> int:
    return execute(settings_from_args(args), args, "bittc sweep " + shlex.join(sys.argv[2:]))
