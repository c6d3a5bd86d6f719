"""`bittc compare`: two sets of closed-loop runs, case by case and per family."""

from __future__ import annotations

import argparse
import json
import math

from bittc_core.errors import CliError
from sim.cli.common import output_file


def add_parser(sub) -> argparse.ArgumentParser:
    p = sub.add_parser(
        "compare",
        help="two sets of suite or run folders side by side: which figures and cases got worse",
        description="Matches the runs of two sets of `bittc suite` or `bittc run` folders by case and seed, "
        "and prints per family, base -> new: threats avoided, false alarms, first warnings at an exact TTC >= 2.1 s, "
        "Euro NCAP points and the summed impact speed, then every case that got worse or better. With "
        "--fail-on-worse it exits with status 1 when anything got worse.",
    )
    p.add_argument("--base", nargs="+", required=True, metavar="DIR", help="the reference set: suite or run folders")
    p.add_argument("--new", nargs="+", required=True, metavar="DIR", help="the set to judge, the same cases")
    p.add_argument(
        "--tol-kph",
        type=float,
        default=0.5,
        metavar="KPH",
        help="an impact speed counts as changed beyond this many km/h (default 0.5)",
    )
    p.add_argument("--markdown", action="store_true", help="print the table as Markdown")
    p.add_argument("--out", default=None, metavar="FILE", help="also write the comparison as JSON (.json)")
    p.add_argument(
        "--fail-on-worse",
        action="store_true",
        help="exit with status 1 when a case or a figure got worse, or a case of --base is missing from --new",
    )
    return p


def run(args) -> int:
    from bittc_core.atomic import write_text_atomic
    from sim.compare import compare, format_comparison, load_runs

    if not (args.tol_kph >= 0 and math.isfinite(args.tol_kph)):
        raise CliError(f"--tol-kph {args.tol_kph!r}: expected a number >= 0")
    out = None if args.out is None else output_file(args.out, (".json",))
    c = compare(load_runs(args.base), load_runs(args.new), args.tol_kph)
    print(format_comparison(c, markdown=args.markdown))
    if out is not None:
        try:
            write_text_atomic(out, json.dumps(c.to_dict(), indent=2) + "\n")
        except OSError as e:
            raise CliError(f"--out {args.out!r}: not writable ({e.strerror})") from None
        print(f"wrote {args.out}")
    return 1 if args.fail_on_worse and not c.passed else 0
