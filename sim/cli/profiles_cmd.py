"""`bittc profiles`: the device latency profiles of `--latency profile:NAME`."""

from __future__ import annotations

import argparse
import textwrap


def add_parser(sub) -> argparse.ArgumentParser:
    return sub.add_parser(
        "profiles",
        help="list the device latency profiles (cost terms per estimator family)",
        description="Lists the named device profiles that --latency profile:NAME reads, with "
        "where each number comes from (bittc profile measures a new one).",
    )


def run(args) -> int:
    from sim.job_timing import JobSetting
    from sim.latency import MEASURED_PROFILES_DIR, PROFILES_FILE, named_profiles

    # the default camera's streaming jobs at K = 4, as the closed loop charges them: the fovea
    # half as wide, running the controller's default fovea fences (sim.job_timing.JobSetting.work)
    wide, fovea = JobSetting(4), JobSetting(4, fovea_zoom=4.0)
    for p in named_profiles().values():
        kind = "measured" if p.measured else "not measured"
        cont = f", continuous {p.continuous_ms:g} ms" if p.continuous_ms is not None else ""
        print(f"{p.name:<22} [{kind}]{cont}")
        for family, c in p.costs.items():
            print(
                f"    {family:<6} L = {c.job_ms:g} + {c.view_ms:g} x views + {c.threshold_ms:g} x thresholds "
                f"+ {c.extract_ms:g} x extractions ms (wide, K = 4: "
                f"{p.latency_ms(wide.work(family, family == 'bittc')):.1f} ms; "
                f"with the default fovea: {p.latency_ms(fovea.work(family, family == 'bittc')):.1f} ms)"
            )
        print(textwrap.fill(p.source, width=96, initial_indent=" " * 4, subsequent_indent=" " * 4))
    print(
        f"(from {PROFILES_FILE} and {MEASURED_PROFILES_DIR}/*.yaml; a file of your own: --latency profile:FILE, "
        "made by `bittc profile --out FILE`)"
    )
    return 0
