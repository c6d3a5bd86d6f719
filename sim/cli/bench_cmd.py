"""`bittc bench`: latency of the estimator vs. number of thresholds (prints only)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from bittc_core.errors import BittcError, CliError
from sim.cli.common import DEFAULT_FOVEA, check_frame_size, output_file, parse_fovea, parse_size

DEFAULT_CONFIG = "cpu-small-corr"


def add_parser(sub) -> argparse.ArgumentParser:
    p = sub.add_parser(
        "bench",
        help="CPU latency of the network vs. number of thresholds",
        description="Streaming latency (96x288 unless --size) for K = 1, 2, 4, 8, 16, 24 thresholds, "
        "binary and continuous, plain and flip-averaged, with the flow baseline timed in the same run. "
        "With --backend torch onnxruntime: both backends timed in the same interleaved rounds, "
        "side by side with their ratios. With --fovea off 4: whole closed-loop jobs instead (the network on "
        "every view plus the geofence controller's own work), per backend x fovea x K, binary and "
        "continuous, in the same interleaved rounds; --out FILE writes them as JSON rows. Several "
        "--onnx folders (e.g. a float32 and an int8 export) are timed side by side as backends "
        "onnxruntime-<precision>; --graphs times each ONNX graph on its own, per folder.",
    )
    p.add_argument(
        "--config",
        default=None,
        help=f"model config of random weights (default {DEFAULT_CONFIG}, the shipped one); not with --weights",
    )
    p.add_argument("--weights", default=None, help="time this checkpoint instead of random weights")
    p.add_argument(
        "--backend",
        nargs="+",
        default=["torch"],
        choices=("torch", "onnxruntime"),
        help="backends to time (default torch); onnxruntime times the shipped weights (or --weights) "
        "exported to --onnx DIR, or to a temporary folder without it",
    )
    p.add_argument(
        "--onnx",
        nargs="+",
        default=None,
        metavar="DIR",
        help="with --backend onnxruntime: folders made by `bittc export --onnx DIR [--int8]`, each timed "
        "as its own backend",
    )
    p.add_argument(
        "--graphs",
        action="store_true",
        help="with --backend onnxruntime: time each graph of each --onnx folder on its own (extractor, "
        "reference, thresholds at K = 4, continuous), wide view and fovea, in interleaved rounds",
    )
    p.add_argument("--calls", type=int, default=30, help="timed calls per setting (default 30)")
    p.add_argument("--threads", type=int, default=2, help="torch / onnxruntime threads (default 2)")
    p.add_argument(
        "--size",
        default="96x288",
        help="frame size HxW [px], multiples of 3 (default 96x288, the shipped weights' camera)",
    )
    p.add_argument(
        "--fovea",
        nargs="+",
        default=None,
        metavar="ZOOM|off",
        help="time whole per-frame jobs with and without a fovea (e.g. off 4) instead of the estimator alone",
    )
    p.add_argument("--out", default=None, metavar="FILE", help="with --fovea: write the rows as JSON (.json)")
    return p


def check_common(args):
    """-> (BenchSettings, backends); every flag checked."""
    from bittc_core.benchmark import BenchSettings
    from bittc_core.model import CONFIGS

    if args.config is not None and args.weights is not None:
        raise CliError(f"--config {args.config!r} with --weights: the checkpoint has its own config; give one of them")
    config = args.config or DEFAULT_CONFIG
    if config not in CONFIGS:
        raise CliError(f"--config {config!r}: expected one of {sorted(CONFIGS)}")
    if args.calls <= 0 or args.threads <= 0:
        raise CliError(f"--calls {args.calls} / --threads {args.threads}: must be > 0")
    backends = list(dict.fromkeys(args.backend))
    if args.onnx is not None and "onnxruntime" not in backends:
        raise CliError("--onnx applies to --backend onnxruntime")
    if args.onnx is not None and len(set(args.onnx)) != len(args.onnx):
        raise CliError(f"--onnx {' '.join(args.onnx)}: a folder given twice")
    if args.graphs and (args.onnx is None or args.fovea is not None):
        raise CliError("--graphs times the graphs of --backend onnxruntime --onnx DIR [DIR ...], without --fovea")
    if "onnxruntime" in backends:
        if args.config is not None:
            raise CliError(
                "--config: the onnxruntime backend times trained weights (--weights, default the shipped ones)"
            )
        try:
            import onnxruntime  # noqa: F401
        except ImportError:
            raise CliError("--backend onnxruntime needs onnxruntime: pip install -e '.[onnx]'") from None
    h, w = parse_size(args.size)
    check_frame_size((h, w), "bittc", f"--size {args.size}", hint="")
    return BenchSettings(config=config, height_px=h, width_px=w, calls=args.calls, threads=args.threads), backends


def view_sizes(size_hw: tuple[int, int], foveas=(None,)) -> list[tuple[int, int]]:
    """(H, W) [px] of the views the estimator sees: the wide view at ``size_hw`` and the fovea
    of each zoom of ``foveas`` (None: no fovea)."""
    from sim.camera import CameraConfig

    sizes = [size_hw]
    for zoom in foveas:
        if zoom is not None:
            fovea = CameraConfig(height_px=size_hw[0], width_px=size_hw[1], fovea_zoom=zoom).fovea()
            sizes.append((fovea.height_px, fovea.width_px))
    return list(dict.fromkeys(sizes))


def estimators_for(backends, weights, onnx, sizes, threads, tmp_dir):
    """backend label -> estimator of the same weights; onnxruntime exports them at every size
    of ``sizes`` into ``tmp_dir`` when no ``onnx`` folders are given. Several folders are
    labelled by their precision: onnxruntime-float32, onnxruntime-int8 (and the folder's
    name where two share one)."""
    import time

    import torch

    from bittc_core.checkpoint import DEFAULT_WEIGHTS
    from bittc_core.estimator import make_estimator

    torch.set_num_threads(threads)
    weights = weights or str(DEFAULT_WEIGHTS)
    out = {}
    for b in backends:
        if b == "torch":
            out[b] = make_estimator("bittc", weights=weights, device="cpu")
            continue
        if onnx is None:
            from bittc_core.export.onnx_export import export_onnx

            t0 = time.perf_counter()
            onnx = [f"{tmp_dir}/onnx"]
            export_onnx(weights, onnx[0], sizes=sizes)
            print(f"exported {weights} to a temporary ONNX folder in {time.perf_counter() - t0:.0f} s")
        ests = [make_estimator("bittc", weights=weights, backend="onnxruntime", onnx=d) for d in onnx]
        precisions = [e.precision for e in ests]
        for d, e in zip(onnx, ests):
            label = b
            if len(ests) > 1:
                label = f"{b}-{e.precision}"
                if precisions.count(e.precision) > 1:
                    label += f"-{Path(d).name}"
            out[label] = e
    return out


def run_jobs(args, settings, backends, ests) -> int:
    """--fovea: whole per-frame jobs per backend x fovea x K (binary: a geofence-controller job;
    continuous: the network's continuous TTC on every view), all in the same interleaved rounds."""
    import json

    from bittc_core.atomic import write_text_atomic
    from sim.job_timing import JobSetting, time_jobs

    foveas = list(dict.fromkeys(parse_fovea(f) for f in args.fovea))
    jobs = [
        *(JobSetting(k, z) for z in foveas for k in settings.thresholds),
        *(JobSetting(0, z, continuous=True) for z in foveas),
    ]
    rows = []
    for backend, est in ests.items():
        ms = time_jobs(est, jobs, (settings.height_px, settings.width_px), settings.calls)
        rows += [
            {
                "backend": backend,
                "fovea_zoom": j.fovea_zoom,
                "num_alphas": j.num_alphas if not j.continuous else None,
                "output": "continuous" if j.continuous else "binary",
                "tta": "none",
                "median_ms": t,
            }
            for j, t in zip(jobs, ms)
        ]
    print(
        f"whole per-frame jobs at {settings.height_px}x{settings.width_px} px, {settings.threads} threads, "
        f"{settings.calls} interleaved rounds (the estimator on every view + the geofence controller)"
    )
    base = foveas[0]
    width = max(12, *(len(b) + 2 for b in ests))
    per = "/ " + ("off" if base is None else f"x{base:g}")
    print(f"{'backend':<{width}}{'fovea':>7}{'K':>6}{'median ms':>11}{per:>9}")
    ref = {(r["backend"], r["output"], r["num_alphas"]): r["median_ms"] for r in rows if r["fovea_zoom"] == base}
    for r in rows:
        k = "cont" if r["output"] == "continuous" else str(r["num_alphas"])
        ratio = r["median_ms"] / ref[(r["backend"], r["output"], r["num_alphas"])]
        zoom = "off" if r["fovea_zoom"] is None else f"x{r['fovea_zoom']:g}"
        print(f"{r['backend']:<{width}}{zoom:>7}{k:>6}{r['median_ms']:>11.2f}{ratio:>9.2f}")
    if args.out:
        write_text_atomic(Path(args.out), json.dumps({"rows": rows}, indent=2) + "\n")
        print(f"wrote {args.out}")
    return 0


def run(args) -> int:
    import tempfile

    from bittc_core.benchmark import run_backend_comparison, run_benchmark

    settings, backends = check_common(args)
    if args.out is not None and args.fovea is None:
        raise CliError("--out applies with --fovea (the job benchmark)")
    if args.fovea is not None:
        if args.out is not None:
            output_file(args.out, (".json",))
        if args.config is not None:
            raise CliError("--config with --fovea: the job benchmark times trained weights (--weights)")
        foveas = [parse_fovea(v) for v in args.fovea]  # every value checked before anything is timed
        sizes = view_sizes((settings.height_px, settings.width_px), foveas)
        with tempfile.TemporaryDirectory(prefix="bittc_bench_") as tmp:
            ests = estimators_for(backends, args.weights, args.onnx, sizes, settings.threads, tmp)
            return run_jobs(args, settings, backends, ests)
    if args.graphs:
        from bittc_core.benchmark import time_graphs

        sizes = view_sizes((settings.height_px, settings.width_px), [parse_fovea(DEFAULT_FOVEA)])
        ests = estimators_for(["onnxruntime"], args.weights, args.onnx, sizes, settings.threads, None)
        time_graphs(settings, ests, sizes)
        return 0
    if backends == ["torch"]:
        run_benchmark(settings, weights=args.weights)
        return 0
    with tempfile.TemporaryDirectory(prefix="bittc_bench_") as tmp:
        sizes = [(settings.height_px, settings.width_px)]
        ests = estimators_for(backends, args.weights, args.onnx, sizes, settings.threads, tmp)
        run_backend_comparison(settings, ests)
    return 0


def main(argv: list[str] | None = None) -> int:
    """Stand-alone entry (bench/bench_network.py) without the other subcommands."""
    parser = argparse.ArgumentParser(prog="bench_network")
    sub = parser.add_subparsers(dest="command", required=True)
    add_parser(sub)
    args = parser.parse_args(["bench", *(sys.argv[1:] if argv is None else argv)])
    try:
        return run(args)
    except BittcError as err:
        print(f"bench: error: {err}", file=sys.stderr)
        return 2
