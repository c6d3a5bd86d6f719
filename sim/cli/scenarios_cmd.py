"""`bittc scenarios`: list the bundled scenarios, one line each."""

from __future__ import annotations

import argparse

import scenarios


def add_parser(sub) -> argparse.ArgumentParser:
    p = sub.add_parser("scenarios", help="list bundled scenarios")
    p.add_argument("--cases", action="store_true", help="list every expanded case, not only families")
    p.add_argument(
        "--suites",
        action="store_true",
        help="list the named suites (ncap, near, benign, vru, junction, benign-vru, all, demo)",
    )
    return p


def run(args) -> int:
    cat = scenarios.bundled()
    if args.suites:
        for name, what in scenarios.SUITES.items():
            print(f"{name:<10} {len(scenarios.resolve_suite(name)):>3} cases  {what}")
        return 0
    for family, cases in cat.families.items():
        kind = "threat" if cases[0].threat else "benign"
        if args.cases:
            for c in cases:
                print(f"{c.name:<28} {kind:<7} {c.description}")
        else:
            names = cases[0].name if len(cases) == 1 else f"{cases[0].name} .. {cases[-1].name} ({len(cases)} cases)"
            print(f"{family:<28} {kind:<7} {cases[0].description}  [{names}]")
    return 0
