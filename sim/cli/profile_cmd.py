"""`bittc profile --out FILE`: measure this machine's latency profile for `--latency profile:FILE`."""

from __future__ import annotations

import argparse

from sim.cli.common import add_fovea_flag


def add_parser(sub) -> argparse.ArgumentParser:
    p = sub.add_parser(
        "profile",
        help="measure this machine's latency profile (the cost terms of a closed-loop job) into a file",
        description="Times whole geofence-controller jobs (the estimator on every view plus the controller's "
        "own work) for the network and the flow baseline: streaming and after a skip, wide view alone and "
        "with a fovea, several K (interleaved rounds, as bittc bench); fits each family's cost terms "
        "L = job + views * view + thresholds * threshold + extractions * extract [ms] by non-negative least "
        "squares and writes FILE (YAML: the terms, the raw timings, the fit, the machine, the package versions, "
        "the date). `bittc run` and `bittc sweep` read it with --latency profile:FILE.",
    )
    p.add_argument("--out", required=True, metavar="FILE", help="the profile file to write (.yaml)")
    p.add_argument("--name", default=None, help="a label for the profile (default: this machine's host name)")
    p.add_argument(
        "--backend",
        default="torch",
        choices=("torch", "onnxruntime"),
        help="the backend to time (default torch); onnxruntime needs --onnx DIR",
    )
    p.add_argument("--onnx", default=None, metavar="DIR", help="with --backend onnxruntime: `bittc export --onnx DIR`")
    p.add_argument("--weights", default=None, help="checkpoint (default: the shipped weights)")
    p.add_argument("--size", default="96x288", help="frame size HxW [px], multiples of 3 (default 96x288)")
    p.add_argument("--threads", type=int, default=2, help="threads of the backend (default 2)")
    p.add_argument("--calls", type=int, default=30, help="timed calls per setting (default 30)")
    add_fovea_flag(p)
    return p


def _check(args):
    """-> (out path, (H, W), the fovea's zoom); every flag checked before anything is timed."""
    from bittc_core.errors import CliError
    from sim.cli.common import check_frame_size, output_file, parse_fovea, parse_size

    out = output_file(args.out, (".yaml", ".yml"))
    if args.calls <= 0 or args.threads <= 0:
        raise CliError(f"--calls {args.calls} / --threads {args.threads}: must be > 0")
    h, w = parse_size(args.size)
    check_frame_size((h, w), "bittc", f"--size {args.size}", hint="")
    zoom = parse_fovea(args.fovea) or 4.0  # the second view's zoom does not change its cost
    return out, (h, w), zoom


def _fit(jobs: dict, measured: dict, size_hw: tuple[int, int]) -> tuple[dict, dict, list[dict]]:
    """family -> settings and medians [ms] -> (family -> cost terms, family -> fit residuals, timing rows)."""
    from sim.cost_model import COST_TERMS
    from sim.profile_file import fit_cost_terms

    doc_terms, fits, timings = {}, {}, []
    for family, settings in jobs.items():
        rows = [(s.work(family, family == "bittc", size_hw), t) for s, t in zip(settings, measured[family])]
        terms, rms, worst = fit_cost_terms(rows)
        doc_terms[family] = {k: getattr(terms, k) for k in COST_TERMS}
        fits[family] = {"rms_residual_ms": round(rms, 3), "max_residual_ms": round(worst, 3)}
        timings += [
            {"estimator": family, "views": wk.views, "thresholds": wk.thresholds, "extractions": wk.extractions}
            | {"median_ms": t}
            for wk, t in rows
        ]
    return doc_terms, fits, timings


def _print_fit(doc_terms: dict, fits: dict, timings: list[dict]) -> None:
    from sim.cost_model import CostTerms, JobWork

    print(f"{'estimator':<10}{'views':>6}{'thr':>7}{'extr':>6}{'median ms':>11}{'fit ms':>8}")
    for r in timings:
        wk = JobWork(r["estimator"], r["views"], r["thresholds"], r["extractions"])
        fit = CostTerms(**doc_terms[r["estimator"]]).latency_ms(wk)
        print(
            f"{r['estimator']:<10}{wk.views:>6}{wk.thresholds:>7.3g}{wk.extractions:>6.3g}{r['median_ms']:>11.2f}{fit:>8.2f}"
        )
    for family, t in doc_terms.items():
        terms = ", ".join(f"{k} {v:.2f}" for k, v in t.items())
        print(f"{family}: {terms} (rms {fits[family]['rms_residual_ms']:.2f} ms)")


def run(args) -> int:
    from pathlib import Path

    import torch

    from bittc_core import profiling
    from bittc_core.checkpoint import DEFAULT_WEIGHTS, load_checkpoint, release_name
    from bittc_core.estimator import make_estimator
    from bittc_core.export.manifest import sha256_file
    from sim.cli.common import backend_kwargs
    from sim.job_timing import JobSetting, profile_settings, time_jobs
    from sim.profile_file import write_profile_file

    out, (h, w), zoom = _check(args)
    weights = args.weights or str(DEFAULT_WEIGHTS)
    torch.set_num_threads(args.threads)
    est = make_estimator("bittc", device="cpu", **({"weights": weights} | backend_kwargs(args)))
    jobs = {"bittc": profile_settings("bittc", zoom), "flow": profile_settings("flow", zoom)}
    print(
        f"timing {args.backend} and flow jobs at {h}x{w} px, {args.threads} threads: "
        f"{sum(map(len, jobs.values()))} settings and continuous, {args.calls} calls each, interleaved ..."
    )
    net_ms = time_jobs(est, [*jobs["bittc"], JobSetting(0, continuous=True)], (h, w), args.calls)
    measured = {"bittc": net_ms[:-1], "flow": time_jobs(make_estimator("flow"), jobs["flow"], (h, w), args.calls)}
    doc_terms, fits, timings = _fit(jobs, measured, (h, w))
    m = profiling.machine()
    doc = {
        "name": args.name or m["node"] or "this-machine",
        **doc_terms,
        "continuous_ms": net_ms[-1],
        "measured": True,
        "source": f"`bittc profile` on {m['processor']} ({m['cpus']} CPUs), {args.backend} with {args.threads} "
        f"threads, {h}x{w} px, weights {Path(weights).name}: non-negative least squares of the medians of "
        f"{len(timings)} kinds of whole controller jobs (wide and fovea x{zoom:g}, streaming and after a skip), "
        f"{profiling.today()}",
        "timings_ms": timings,
        "fit": fits,
        "backend": args.backend,
        "size_px": [h, w],
        "threads": args.threads,
        "weights": {
            "file": Path(weights).name,
            "sha256": sha256_file(weights),
            "release": release_name(load_checkpoint(weights)),
        },
        "machine": m,
        "versions": profiling.versions(args.backend),
        "date": profiling.today(),
    }
    write_profile_file(out, doc)
    _print_fit(doc_terms, fits, timings)
    print(f"continuous {net_ms[-1]:.1f} ms per view; wrote {out}; use it with --latency profile:{out}")
    return 0
