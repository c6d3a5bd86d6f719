"""`bittc profile --out FILE`: measure this machine's latency profile for `--latency profile:FILE`."""

from __future__ import annotations

import argparse


def add_parser(sub) -> argparse.ArgumentParser:
    p = sub.add_parser(
        "profile",
        help="measure this machine's latency profile (L = a + b*K) into a file",
        description="Times the network in streaming mode for K = 1, 2, 4, 8, 16, 24 and in continuous "
        "mode (interleaved rounds, as bittc bench), fits L = a + b * K by least squares and writes "
        "FILE (YAML: the fit, the raw timings, the machine, the package versions, the date). "
        "`bittc run` and `bittc sweep` read it with --latency profile:FILE.",
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
    p.add_argument("--calls", type=int, default=30, help="timed calls per K (default 30)")
    return p


def run(args) -> int:
    from pathlib import Path

    from bittc_core import profiling
    from bittc_core.benchmark import BenchSettings
    from bittc_core.checkpoint import DEFAULT_WEIGHTS, load_checkpoint, release_name
    from bittc_core.cli.common import backend_kwargs, check_frame_size, parse_size
    from bittc_core.errors import CliError
    from bittc_core.estimator import make_estimator
    from bittc_core.export.manifest import sha256_file
    from sim.profile_file import fit_latency, write_profile_file

    out = Path(args.out)
    if out.suffix not in (".yaml", ".yml"):
        raise CliError(f"--out {args.out!r}: expected a .yaml file")
    if not out.parent.is_dir():
        raise CliError(f"--out {args.out!r}: folder {str(out.parent)!r} does not exist")
    if args.calls <= 0 or args.threads <= 0:
        raise CliError(f"--calls {args.calls} / --threads {args.threads}: must be > 0")
    h, w = parse_size(args.size)
    check_frame_size((h, w), "bittc", f"--size {args.size}", hint="")
    weights = args.weights or str(DEFAULT_WEIGHTS)
    import torch

    torch.set_num_threads(args.threads)
    est = make_estimator("bittc", device="cpu", **({"weights": weights} | backend_kwargs(args)))
    s = BenchSettings(height_px=h, width_px=w, calls=args.calls, threads=args.threads)
    print(
        f"timing {args.backend} at {h}x{w} px, {args.threads} threads, K = {', '.join(map(str, s.thresholds))} "
        f"and continuous ({args.calls} calls each, interleaved) ..."
    )
    t = profiling.measure(est, s)
    a, b, rms, worst = fit_latency(t["binary"])
    m = profiling.machine()
    name = args.name or m["node"] or "this-machine"
    ckpt = load_checkpoint(weights)
    doc = {
        "name": name,
        "a_ms": round(a, 3),
        "b_ms": round(b, 3),
        "continuous_ms": t["continuous"],
        "measured": True,
        "source": f"`bittc profile` on {m['processor']} ({m['cpus']} CPUs), {args.backend} with {args.threads} "
        f"threads, {h}x{w} px, weights {Path(weights).name}: least-squares fit of the streaming "
        f"medians over K = {', '.join(map(str, s.thresholds))}, {profiling.today()}",
        "timings_ms": t,
        "fit": {"rms_residual_ms": round(rms, 3), "max_residual_ms": round(worst, 3)},
        "backend": args.backend,
        "size_px": [h, w],
        "threads": args.threads,
        "weights": {"file": Path(weights).name, "sha256": sha256_file(weights), "release": release_name(ckpt, weights)},
        "machine": m,
        "versions": profiling.versions(args.backend),
        "date": profiling.today(),
    }
    write_profile_file(out, doc)
    print(f"{'K':>4} {'median ms':>10} {'fit ms':>8}")
    for k, v in t["binary"].items():
        print(f"{k:>4} {v:>10.2f} {a + b * k:>8.2f}")
    print(f"L = {a:.2f} + {b:.2f} * K ms (rms residual {rms:.2f} ms); continuous {t['continuous']:.1f} ms")
    print(f"wrote {out}; use it with --latency profile:{out}")
    return 0
