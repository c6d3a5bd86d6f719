"""`bittc data stats DIR`: counts and the tau histogram of a dataset."""

from __future__ import annotations

import argparse
from pathlib import Path

from bittc_core.errors import CliError


def add_parser(sub) -> argparse.ArgumentParser:
    p = sub.add_parser("data", help="inspect a generated dataset")
    dsub = p.add_subparsers(dest="data_command", metavar="ACTION", required=True)
    s = dsub.add_parser("stats", help="counts per split and the tau histogram over actor pixels")
    s.add_argument("dir", help="a dataset folder made by `bittc generate`")
    s.add_argument("--json", action="store_true", help="print the statistics as JSON")
    return p


def run(args) -> int:
    import json

    from bittc_core.data.card import scan, summarize

    root = Path(args.dir)
    if not (root / "generation.yaml").exists():
        raise CliError(f"{args.dir!r}: not a bittc dataset (no generation.yaml)")
    stats = summarize(scan(root))
    if args.json:
        print(json.dumps(stats, indent=2))
        return 0
    for split, s in stats["splits"].items():
        print(f"{split:<6} {s['samples']:>8} samples  seeds {s['seed_min']}..{s['seed_max']}  {s['actors']} actors")
    hist = stats["tau_histogram_actor_px"]
    total = sum(hist.values()) or 1
    print("tau over actor pixels (latest pair):")
    for k, v in hist.items():
        print(f"  {k:>14} {v:>12} {100 * v / total:6.2f} %  {'#' * int(60 * v / total)}")
    return 0
