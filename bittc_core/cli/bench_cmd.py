"""`bittc bench`: latency of the estimator vs. number of thresholds (prints only)."""

from __future__ import annotations

import argparse
import sys

from bittc_core.cli.common import check_frame_size, parse_size
from bittc_core.errors import CliError


def add_parser(sub) -> argparse.ArgumentParser:
    p = sub.add_parser("bench", help="CPU latency of the network vs. number of thresholds",
                       description="Streaming latency (96x288 unless --size) for K = 1, 2, 4, 8, 16, 24 thresholds, "
                       "binary and continuous, plain and flip-averaged, with the flow baseline timed in the same run.")
    p.add_argument("--config", default="cpu-small-corr", help="model config (ignored with --weights; default: the shipped one)")
    p.add_argument("--weights", default=None, help="time this checkpoint instead of random weights")
    p.add_argument("--calls", type=int, default=30, help="timed calls per setting (default 30)")
    p.add_argument("--threads", type=int, default=2, help="torch threads (default 2)")
    p.add_argument("--size", default="96x288", help="frame size HxW [px], multiples of 3 (default 96x288, the "
                   "shipped weights' camera)")
    return p


def run(args) -> int:
    from bittc_core.benchmark import BenchSettings, run_benchmark
    from bittc_core.model import CONFIGS

    if args.config not in CONFIGS:
        raise CliError(f"--config {args.config!r}: expected one of {sorted(CONFIGS)}")
    if args.calls <= 0 or args.threads <= 0:
        raise CliError(f"--calls {args.calls} / --threads {args.threads}: must be > 0")
    h, w = parse_size(args.size)
    check_frame_size((h, w), "bittc", f"--size {args.size}", hint="")
    run_benchmark(BenchSettings(config=args.config, height_px=h, width_px=w, calls=args.calls,
                                threads=args.threads), weights=args.weights)
    return 0


def main(argv: list[str] | None = None) -> int:
    """Stand-alone entry (bench/bench_network.py) without the other subcommands."""
    parser = argparse.ArgumentParser(prog="bench_network")
    sub = parser.add_subparsers(dest="command", required=True)
    add_parser(sub)
    args = parser.parse_args(["bench", *(sys.argv[1:] if argv is None else argv)])
    try:
        return run(args)
    except CliError as err:
        print(f"bench: error: {err}", file=sys.stderr)
        return 2
