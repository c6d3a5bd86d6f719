"""`bittc profiles`: the device latency profiles of `--latency profile:NAME`."""

from __future__ import annotations

import argparse
import textwrap


def add_parser(sub) -> argparse.ArgumentParser:
    return sub.add_parser(
        "profiles",
        help="list the device latency profiles (L = a + b*K ms)",
        description="Lists the named device profiles that --latency profile:NAME reads, with "
        "where each number comes from (bittc profile measures a new one).",
    )


def run(args) -> int:
    from sim.latency import MEASURED_PROFILES_DIR, PROFILES_FILE, named_profiles

    for p in named_profiles().values():
        kind = "measured" if p.measured else "not measured"
        cont = f", continuous {p.continuous_ms:g} ms" if p.continuous_ms is not None else ""
        print(f"{p.name:<22} L = {p.a_ms:g} + {p.b_ms:g} * K ms{cont}  [{kind}]")
        print(textwrap.fill(p.source, width=96, initial_indent=" " * 4, subsequent_indent=" " * 4))
    print(
        f"(from {PROFILES_FILE} and {MEASURED_PROFILES_DIR}/*.yaml; a file of your own: --latency profile:FILE, "
        "made by `bittc profile --out FILE`)"
    )
    return 0
