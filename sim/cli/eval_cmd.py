"""`bittc eval --data DIR --method {bittc,flow,oracle,oracle-auc}`: metrics of an estimator.

Prints a table and writes a JSON file (--out, default eval_<method>_<split>.json)
with miou, mid, error_rate, actor_iou, latency_ms and a breakdown of where the
errors are (see ``bittc_core.metrics``).
Latency: wall time per pair of the estimator calls (geofence for all metric
thresholds + continuous), frames fed in dataset order.

`bittc eval --scenarios SUITE --method {bittc,flow}` instead renders the cases of a
suite (`bittc scenarios --suites`) or scenario open loop and measures the geofences on
what braking needs: per case and threshold the fence lag of the critical actor, the
share of it inside each fence against its exact TTC (--plot), and the stray in-path
evidence of the benign cases (see ``sim.scenario_eval``); JSON (default
eval_<method>_scenarios_<suite>.json) and a table.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from bittc_core.atomic import write_text_atomic
from bittc_core.errors import CliError, ConfigError
from sim.cli.common import (
    TTA_MODES,
    add_backend_flags,
    add_device_flag,
    add_fovea_flag,
    add_seed_flag,
    backend_kwargs,
    check_device,
    check_seed,
    flag_error,
    output_file,
    parse_fovea,
)

METHODS = ("bittc", "flow", "oracle", "oracle-auc")
SPLITS = ("train", "val", "test")


def add_parser(sub) -> argparse.ArgumentParser:
    from sim.cli.eval_kitti import add_kitti_flags

    p = sub.add_parser("eval", help="evaluate an estimator on a dataset split", description=__doc__.split("\n\n", 1)[1])
    p.add_argument("--data", default=None, help="dataset folder, or 'synthetic'")
    p.add_argument(
        "--scenarios",
        default=None,
        metavar="SUITE",
        help="instead of --data: a suite (ncap, near, benign, vru, junction, benign-vru, all, demo), a bundled "
        "name or a YAML file",
    )
    add_kitti_flags(p)
    p.add_argument(
        "--tau",
        type=float,
        nargs="+",
        default=[0.9, 1.6, 2.4],
        metavar="S",
        help="with --scenarios or --kitti-raw: the fences' thresholds [s] (default 0.9 1.6 2.4)",
    )
    p.add_argument("--plot", default=None, help="with --scenarios: also write this PNG of the inside-share curve")
    add_fovea_flag(p)
    add_seed_flag(p, "with --scenarios: scenery seed")
    p.add_argument(
        "--frame-stride",
        type=int,
        default=None,
        metavar="N",
        help="with --scenarios: pair each frame with the one N frames before (default 3, the geofence "
        "controller's); with --data: the dataset's pairs span N of the network's frame intervals (default 1)",
    )
    p.add_argument(
        "--method",
        required=True,
        choices=METHODS,
        help="bittc, flow, oracle, or oracle-auc (exact geofences; "
        "continuous output from their AUC at the shipped network's levels: the floor of its AUC)",
    )
    p.add_argument("--weights", default=None, help="checkpoint for bittc (default: shipped weights)")
    p.add_argument(
        "--out",
        default=None,
        metavar="FILE",
        help="JSON file to write, replaced if it exists (default: eval_METHOD_SPLIT.json, or "
        "eval_METHOD_scenarios_SUITE.json, in the current folder; refused if that file exists)",
    )
    p.add_argument("--split", default="test", choices=SPLITS, help="train, val or test (default test)")
    p.add_argument("--limit", type=int, default=None, help="evaluate the first N pairs only")
    p.add_argument(
        "--tta",
        default="none",
        choices=TTA_MODES,
        help="bittc only: 'flip' averages the network over the plain "
        "and the mirrored frames (1.4-2.2x the latency); default 'none'",
    )
    add_device_flag(p)
    add_backend_flags(p)
    return p


def _check(args) -> Path:
    if sum(x is not None for x in (args.data, args.scenarios, args.kitti_raw)) != 1:
        raise CliError(
            "give --data DIR (a dataset split), --scenarios SUITE (scenario cases) or --kitti-raw DIR (a drive), "
            "one of them"
        )
    if args.strides is not None and args.kitti_raw is None:
        raise CliError("--strides applies to --kitti-raw")
    if args.frame_stride is not None and args.kitti_raw is not None:
        raise CliError("--frame-stride applies to --scenarios or --data (--kitti-raw pairs by --strides)")
    if args.method not in METHODS:
        raise CliError(f"--method {args.method!r}: expected one of {METHODS}")
    if args.split not in SPLITS:
        raise CliError(f"--split {args.split!r}: expected one of {SPLITS}")
    if args.limit is not None and args.limit <= 0:
        raise CliError(f"--limit {args.limit}: must be > 0")
    if args.weights is not None and args.method != "bittc":
        raise CliError(f"--weights applies to --method bittc only, not {args.method!r}")
    if args.tta not in TTA_MODES:
        raise CliError(f"--tta {args.tta!r}: expected one of {TTA_MODES}")
    if args.tta != "none" and args.method != "bittc":
        raise CliError(f"--tta {args.tta!r} applies to --method bittc only, not {args.method!r}")
    check_device(args.device)
    args.backend_kw = {"weights": args.weights} | backend_kwargs(args, args.method)
    if args.kitti_raw is not None:
        from sim.cli.eval_kitti import check_kitti

        check_kitti(args)
    if args.scenarios is not None:
        if args.method not in ("bittc", "flow"):
            raise CliError(
                f"--method {args.method!r}: --scenarios evaluates bittc or flow (the oracle reads the "
                "dataset's ground truth)"
            )
        from controllers.geofence import check_thresholds

        try:
            args.tau = check_thresholds(args.tau)
        except ConfigError as e:
            raise CliError(f"--tau: {e}") from None
        check_seed(args.seed)
        from controllers.geofence import DEFAULT_FRAME_STRIDE, check_frame_stride

        if args.frame_stride is None:
            args.frame_stride = DEFAULT_FRAME_STRIDE
        try:
            check_frame_stride(args.frame_stride)
        except ConfigError as e:
            raise CliError(f"--frame-stride: {e}") from None
        if args.plot is not None and not args.plot.endswith(".png"):
            raise CliError(f"--plot {args.plot!r}: expected a .png file")
        args.fovea_zoom = parse_fovea(args.fovea)
    default = (
        f"eval_{args.method}_scenarios_{Path(args.scenarios).stem}.json"
        if args.scenarios
        else f"eval_{args.method}_kitti_{Path(args.kitti_raw).name}.json"
        if args.kitti_raw
        else f"eval_{args.method}_{args.split}.json"
    )
    out = Path(args.out or default)
    if args.out is None and out.exists():
        raise CliError(f"{default!r} exists (an earlier result); pass --out {default} to replace it, or another --out")
    return output_file(str(out), (".json",))


def run_scenarios(args, out: Path) -> int:
    import os

    import scenarios
    from bittc_core.estimator import make_estimator
    from sim import scenario_eval
    from sim.camera import CameraConfig

    cases = scenarios.resolve_suite(args.scenarios)
    estimator = make_estimator(args.method, device=args.device, tta=args.tta, **args.backend_kw)
    from tqdm import tqdm

    results = [
        scenario_eval.evaluate_case(
            c, estimator, args.tau, CameraConfig(fovea_zoom=args.fovea_zoom), args.seed, args.frame_stride
        )
        for c in tqdm(cases, desc="cases", unit="case", leave=False)
    ]
    summary = {
        "method": args.method,
        "weights": args.weights,
        "scenarios": args.scenarios,
        "seed": args.seed,
        "frame_stride": args.frame_stride,
        "fovea_zoom": args.fovea_zoom,
        **scenario_eval.summarize(results, args.tau),
    }
    print(scenario_eval.format_table(summary))
    if args.plot:
        tmp = Path(args.plot).with_name(f".{Path(args.plot).name}.tmp.png")
        scenario_eval.plot_inside_share(summary, tmp, f"{args.method} on {args.scenarios} ({len(cases)} cases)")
        os.replace(tmp, args.plot)
        print(f"wrote {args.plot}")
    write_text_atomic(out, json.dumps(summary, indent=2))
    print(f"wrote {out}")
    return 0


def run(args) -> int:
    out = _check(args)
    if args.scenarios is not None:
        return run_scenarios(args, out)
    if args.kitti_raw is not None:
        from sim.cli.eval_kitti import run_kitti

        return run_kitti(args, out)
    from bittc_core.dataset_eval import evaluate, format_table
    from bittc_core.estimator import make_estimator
    from bittc_core.train.data import open_split

    try:
        dataset = open_split(args.data, args.split)
        estimator = make_estimator(args.method, device=args.device, tta=args.tta, **args.backend_kw)
    except ConfigError as e:
        raise flag_error(e, {"dataset": "--data", "split": "--split", "device": "--device"}) from None
    against = None
    if args.backend != "torch":  # the same pairs on torch, for the agreement
        against = make_estimator(args.method, weights=args.weights, device="cpu", tta=args.tta)
    stride = args.frame_stride or 1  # with --data: the dataset's pairs, at the network's own interval
    result = {
        "method": args.method,
        "split": args.split,
        "data": args.data,
        "weights": args.weights,
        "tta": args.tta,
        "backend": args.backend,
        "frame_stride": stride,
        **evaluate(estimator, dataset, args.limit, against, stride),
    }
    print(format_table(result))
    write_text_atomic(out, json.dumps(result, indent=2))
    print(f"wrote {out}")
    return 0
