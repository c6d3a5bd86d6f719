"""`bittc predict PREV LATEST --out DIR`: geofences and TTC of one pair of image files.

PREV and LATEST are two camera frames (PNG, JPEG, ... read by OpenCV) taken
``frame_dt_s`` apart (0.1 s for the shipped weights: the network reads eta = Z(t1)/Z(t0)
and turns each threshold tau_i [s] into eta_i = tau_i / (tau_i + frame_dt_s)). Every map
lives in LATEST's pixel grid and TTC counts from LATEST's capture time. Writes into DIR,
each file whole or not at all (temporary name, then rename):

* ``prediction.npz``: ``geofence`` (K, H, W) float32 p(0 < tau <= tau_i) in the order of
  ``--tau``, ``thresholds_s`` (K,), ``quantized`` (H, W) int16 bin index over the sorted
  thresholds (0: tau <= the smallest; K: beyond the largest, or receding), ``eta`` and
  ``ttc_s`` (H, W) float32 from the continuous mode (+inf where eta = 1, < 0 receding);
* ``geofence.png``: LATEST with each geofence (p > 0.5) tinted, the shortest on top;
* ``ttc.png``: LATEST with the continuous TTC as the colour map of ``bittc run --video``;
* ``prediction.json``: the settings, the share of pixels inside each geofence and the
  wall time of the calls (``wall_ms``; a process's first call includes start-up costs,
  ``bittc bench`` measures the steady-state latency).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from bittc_core.cli.common import (
    TTA_MODES,
    add_backend_flags,
    add_device_flag,
    backend_kwargs,
    check_device,
    check_frame_size,
    parse_size,
    writable_dir,
)
from bittc_core.errors import CliError

METHODS = ("bittc", "flow")  # the oracle needs ground truth, which image files lack
DEFAULT_TAU_S = (0.5, 1.0, 2.0)
OUTPUT_FILES = ("prediction.npz", "geofence.png", "ttc.png", "prediction.json")


def add_parser(sub) -> argparse.ArgumentParser:
    p = sub.add_parser(
        "predict",
        help="geofences and TTC of one pair of image files",
        description=__doc__.split("\n\n", 1)[1],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("prev", metavar="PREV", help="the earlier frame (image file)")
    p.add_argument("latest", metavar="LATEST", help="the latest frame (image file), frame_dt_s after PREV")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder")
    p.add_argument(
        "--tau",
        type=float,
        nargs="+",
        default=list(DEFAULT_TAU_S),
        metavar="S",
        help="geofence thresholds [s] from the latest frame (default 0.5 1 2)",
    )
    p.add_argument(
        "--method", default="bittc", choices=METHODS, help="bittc (the network, default) or flow (the DIS baseline)"
    )
    p.add_argument("--weights", default=None, help="checkpoint for bittc (default: shipped weights)")
    p.add_argument(
        "--tta",
        default="none",
        choices=TTA_MODES,
        help="bittc only: 'flip' averages over the mirrored frames (default none)",
    )
    add_backend_flags(p)
    p.add_argument(
        "--size",
        default=None,
        metavar="HxW",
        help="resize both frames to HxW px first (area interpolation); default: as they are",
    )
    add_device_flag(p)
    return p


def read_rgb(path: str, flag: str) -> np.ndarray:
    """An image file -> uint8 (H, W, 3) RGB; alpha dropped, grey expanded."""
    import cv2

    if not Path(path).is_file():
        raise CliError(f"{flag} {path!r}: no such file")
    img = cv2.imread(path, cv2.IMREAD_COLOR)
    if img is None:
        raise CliError(f"{flag} {path!r}: not an image OpenCV can read")
    return cv2.cvtColor(img, cv2.COLOR_BGR2RGB)


def geofence_overlay(
    image_rgb: np.ndarray, geofence: np.ndarray, thresholds_s: np.ndarray, alpha: float = 0.5
) -> np.ndarray:
    """Tint each geofence's inside (p > 0.5) from red (shortest tau) to yellow (longest);
    a pixel inside several takes the shortest one's colour (blended once, at ``alpha``)."""
    order = np.argsort(thresholds_s)[::-1]  # longest first, so shorter ones paint over
    k = len(order)
    color = np.zeros(image_rgb.shape, np.float32)
    tinted = np.zeros(image_rgb.shape[:2], bool)
    for rank, i in enumerate(order):
        t = 1.0 - rank / max(k - 1, 1)  # 1 for the longest, 0 for the shortest
        inside = geofence[i] > 0.5
        color[inside] = (255.0, 220.0 * t, 0.0)
        tinted |= inside
    out = image_rgb.astype(np.float32)
    out[tinted] = (1 - alpha) * out[tinted] + alpha * color[tinted]
    return out.round().astype(np.uint8)


def run(args) -> int:
    import cv2

    from bittc_core.data.npz_writer import save_npz
    from bittc_core.estimator import make_estimator
    from bittc_core.estimator.base import as_thresholds, quantize
    from bittc_core.ttc import eta_to_tau
    from sim.video import ttc_overlay

    if args.method not in METHODS:
        raise CliError(f"--method {args.method!r}: expected one of {METHODS}")
    if args.tta not in TTA_MODES:
        raise CliError(f"--tta {args.tta!r}: expected one of {TTA_MODES}")
    check_device(args.device)
    if args.method != "bittc" and (args.weights is not None or args.tta != "none" or args.device != "auto"):
        raise CliError(f"--weights / --tta / --device apply to --method bittc, not {args.method!r}")
    size = parse_size(args.size) if args.size is not None else None
    prev, latest = read_rgb(args.prev, "PREV"), read_rgb(args.latest, "LATEST")
    if prev.shape != latest.shape:
        raise CliError(
            f"PREV is {prev.shape[0]}x{prev.shape[1]} px but LATEST is "
            f"{latest.shape[0]}x{latest.shape[1]} px: the frames must be the same size"
        )
    if size is not None:
        prev, latest = (cv2.resize(img, size[::-1], interpolation=cv2.INTER_AREA) for img in (prev, latest))
    check_frame_size(latest.shape[:2], args.method, "--size" if size is not None else "PREV and LATEST")
    kw = {"weights": args.weights} | backend_kwargs(args, args.method)
    est = make_estimator(args.method, device=args.device, **kw, **({"tta": args.tta} if args.method == "bittc" else {}))
    thr = as_thresholds(args.tau, est.tau_range_s, sorted_=False)
    if len(np.unique(thr)) != len(thr):
        raise CliError(f"--tau {' '.join(f'{t:g}' for t in thr)}: a threshold is given twice")
    out_dir = writable_dir(args.out)  # every check above runs before anything is written

    t0 = time.perf_counter()
    geofence = est.geofence(prev, latest, thr)
    t1 = time.perf_counter()
    eta = est.motion_in_depth(prev, latest)  # the same pair: the network reuses its cached features
    t2 = time.perf_counter()
    ttc = eta_to_tau(eta, est.dt_s).astype(np.float32)
    order = np.argsort(thr)
    quantized = quantize(geofence[order]).astype(np.int16)

    summary = {
        "method": args.method,
        "weights": args.weights,
        "tta": args.tta,
        "backend": args.backend,
        "device": str(getattr(est, "device", "cpu")),
        "prev": args.prev,
        "latest": args.latest,
        "size_hw": list(latest.shape[:2]),
        "frame_dt_s": est.dt_s,
        "thresholds_s": thr.tolist(),
        "inside_share": [round(float((g > 0.5).mean()), 6) for g in geofence],
        "wall_ms": {"geofence": round((t1 - t0) * 1e3, 3), "continuous": round((t2 - t1) * 1e3, 3)},
    }
    tmp = Path(tempfile.mkdtemp(prefix=".predict-", dir=out_dir))
    try:
        save_npz(
            tmp / "prediction.npz",
            {
                "geofence": geofence.astype(np.float32),
                "thresholds_s": thr,
                "quantized": quantized,
                "eta": eta.astype(np.float32),
                "ttc_s": ttc,
            },
        )
        ones = np.ones(ttc.shape, bool)
        for name, img in (
            ("geofence.png", geofence_overlay(latest, geofence, thr)),
            ("ttc.png", ttc_overlay(latest, ttc, ones, ones.astype(np.int32), 0.5, 0.5)),
        ):
            ok, png = cv2.imencode(".png", cv2.cvtColor(img, cv2.COLOR_RGB2BGR))
            if not ok:
                raise CliError(f"could not encode {name}")
            (tmp / name).write_bytes(png.tobytes())
        (tmp / "prediction.json").write_text(json.dumps(summary, indent=1) + "\n")
        for name in OUTPUT_FILES:
            os.replace(tmp / name, out_dir / name)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)

    print(
        f"{args.method}: {latest.shape[0]}x{latest.shape[1]} px, frame_dt_s {est.dt_s:g} s, "
        f"geofences {summary['wall_ms']['geofence']:.1f} ms, continuous {summary['wall_ms']['continuous']:.1f} ms"
    )
    for t, share in zip(thr, summary["inside_share"]):
        print(f"  tau <= {t:g} s: {share:.1%} of the pixels inside")
    print(f"wrote {', '.join(str(out_dir / n) for n in OUTPUT_FILES)}")
    return 0
