"""`bittc eval --kitti-raw DIR --method M`: fence decisions on a KITTI raw drive against its lidar.

The scoring is ``sim.kitti_eval``'s; this module checks the flags and prints and writes the result."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import numpy as np

from bittc_core.errors import CliError

STRIDE_RANGE = (1, 16)


def add_kitti_flags(p) -> None:
    p.add_argument(
        "--kitti-raw",
        default=None,
        metavar="DIR",
        help="instead of --data: a KITTI raw drive (or `bittc run --export-kitti DIR`), its lead's TTC from the lidar",
    )
    p.add_argument(
        "--strides",
        type=int,
        nargs="+",
        default=None,
        metavar="K",
        help="with --kitti-raw: pair frames K apart, each read as the network's frame interval (default 1 to 16)",
    )


def check_kitti(args) -> None:
    from controllers.geofence import check_thresholds

    if args.method not in ("bittc", "flow"):
        raise CliError(f"--method {args.method!r}: --kitti-raw evaluates bittc or flow (a drive has no exact maps)")
    strides = args.strides or list(range(STRIDE_RANGE[0], STRIDE_RANGE[1] + 1))
    bad = [k for k in strides if not STRIDE_RANGE[0] <= k <= STRIDE_RANGE[1]]
    if bad or len(set(strides)) != len(strides):
        raise CliError(
            f"--strides {' '.join(map(str, strides))}: distinct integers in [{STRIDE_RANGE[0]}, {STRIDE_RANGE[1]}]"
        )
    args.strides = tuple(sorted(strides))
    from sim.cli.common import parse_fovea

    args.fovea_zoom = parse_fovea(args.fovea)
    try:
        args.tau = check_thresholds(args.tau)
    except ValueError as e:
        raise CliError(f"--tau: {e}") from None


def _truth_file(folder: Path, n: int) -> np.ndarray | None:
    from sim.kitti_export import TRUTH_FILE

    p = folder / TRUTH_FILE
    if not p.is_file():
        return None
    rows = list(csv.DictReader(p.open()))
    if len(rows) != n:
        raise CliError(f"--kitti-raw: {p} has {len(rows)} rows for {n} frames")
    return np.array([float(r["critical_ttc_s"]) if r["critical_ttc_s"] else np.nan for r in rows])


def run_kitti(args, out: Path) -> int:
    from bittc_core.atomic import write_text_atomic
    from bittc_core.estimator import make_estimator
    from sim.kitti_eval import KittiEvalSettings, lidar_truth, pair_rows, summarize, truth_check
    from sim.kitti_raw import read_drive

    drive = read_drive(args.kitti_raw)  # a FootageError names the file or key
    estimator = make_estimator(args.method, device=args.device, tta=args.tta, **args.backend_kw)
    settings = KittiEvalSettings(thresholds_s=tuple(args.tau), strides=args.strides, fovea_zoom=args.fovea_zoom)
    truth = lidar_truth(drive)  # every scan read and fitted once, for the scores and the check
    rows = pair_rows(drive, estimator, settings, truth)
    result = {
        "method": args.method,
        "weights": args.weights,
        "kitti_raw": str(args.kitti_raw),
        "frames": len(drive.times_s),
        "fovea_zoom": args.fovea_zoom,
        **summarize(rows, settings, estimator.tau_range_s),
    }
    exported = _truth_file(Path(args.kitti_raw), len(drive.times_s))
    if exported is not None:
        result["lidar_truth_vs_export"] = truth_check(drive, truth[1], exported)
    views = "wide view" + ("" if args.fovea_zoom is None else f" + fovea x{args.fovea_zoom:g}")
    print(
        f"{args.method} on {args.kitti_raw}, {views}: {len(rows)} pairs (strides {', '.join(map(str, args.strides))})"
    )
    print(f"{'fence':>7}{'in truth':>10}{'accuracy':>10}{'misses':>8}{'false':>7}{'road false':>12}")
    for t, r in result["thresholds"].items():
        road = "" if r["road_false_fence_share"] is None else f"{r['road_false_fence_share']:.2%}"
        acc = "" if r["accuracy"] is None else f"{r['accuracy']:.1%}"
        print(f"{t + ' s':>7}{r['pairs_inside_in_truth']:>10}{acc:>10}{r['misses']:>8}{r['false_alarms']:>7}{road:>12}")
    if "continuous" in result:
        c = result["continuous"]
        print(f"continuous TTC: Spearman {c['spearman']}, median ratio {c['median_ratio']} over {c['pairs']} pairs")
    if "lidar_truth_vs_export" in result:
        c = result["lidar_truth_vs_export"]
        print(f"lidar TTC against the export's exact TTC (< {c['below_s']:g} s): max error {c['relative_error_max']}")
    buf = io.StringIO()
    if rows:
        w = csv.DictWriter(buf, fieldnames=list(dict.fromkeys(k for r in rows for k in r)), restval="")
        w.writeheader()
        w.writerows(rows)
    write_text_atomic(out.with_suffix(".pairs.csv"), buf.getvalue())
    write_text_atomic(out, json.dumps(result, indent=2))
    print(f"wrote {out} and {out.with_suffix('.pairs.csv')}")
    return 0
