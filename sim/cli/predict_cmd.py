"""`bittc predict PREV LATEST --out DIR`: geofences and TTC of one pair of image files
(`bittc predict CLIP --out DIR`: of every frame of a video or a folder of frames, see
``sim.cli.predict_clip``).

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

With ``--fovea ZOOM`` on a high-resolution pair (a 375x1242 KITTI-like frame, say) and
``--size HxW`` (the network's size): the wide view is the whole frame resized to HxW; the
fovea is the crop of (native height / ZOOM) x (native width / ZOOM) pixels around the
image centre (``--fovea-center U V`` [native px] moves it; the window is kept inside the
frame) resized to HxW, i.e. the view of a ZOOM-times longer lens. A zoom whose crop has
fewer native pixels than HxW (it would be upsampled) is refused. The fovea's maps go into
``prediction.npz`` as ``fovea_geofence``, ``fovea_eta``, ``fovea_ttc_s``, its pictures into
``fovea_geofence.png`` and ``fovea_ttc.png``, its crop box into ``prediction.json``.
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

from bittc_core.errors import CliError
from sim.cli.clip_flags import add_clip_flags, check_pair_mode, fovea_box
from sim.cli.common import (
    TTA_MODES,
    add_backend_flags,
    add_device_flag,
    backend_kwargs,
    check_device,
    check_frame_size,
    parse_size,
    writable_dir,
)
from sim.cli.predict_clip import run_clip
from sim.footage_views import crop_view
from sim.video import threshold_overlay as geofence_overlay

DEFAULT_TAU_S = (0.5, 1.0, 2.0)  # [s] a pair's default fences
METHODS = ("bittc", "flow")  # the oracle needs ground truth, which image files lack
OUTPUT_FILES = ("prediction.npz", "geofence.png", "ttc.png", "prediction.json")


def add_parser(sub) -> argparse.ArgumentParser:
    p = sub.add_parser(
        "predict",
        help="geofences and TTC of one pair of image files, or of every frame of a clip",
        description=__doc__.split("\n\n", 1)[1],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("prev", metavar="PREV|CLIP", help="the earlier frame (image file), or a clip (video or folder)")
    p.add_argument(
        "latest", metavar="LATEST", nargs="?", default=None, help="the latest frame (image file), frame_dt_s after PREV"
    )
    p.add_argument("--out", required=True, metavar="DIR", help="output folder")
    p.add_argument(
        "--tau",
        type=float,
        nargs="+",
        default=None,
        metavar="S",
        help="geofence thresholds [s] from the latest frame (default 0.5 1 2; a clip: the geofence controller's "
        "4 default fences, 0.8 to 2.8 s, which stride 3 reaches)",
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
    p.add_argument(
        "--fovea",
        default="off",
        metavar="ZOOM|off",
        help="also a fovea: the native crop of 1/ZOOM of the frame around its centre, resized to --size (default off)",
    )
    p.add_argument(
        "--fovea-center",
        type=float,
        nargs=2,
        default=None,
        metavar=("U", "V"),
        help="the fovea's centre [native px, column row] (default: the image centre)",
    )
    add_device_flag(p)
    add_clip_flags(p)
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


def _check_flags(args) -> tuple[tuple[int, int] | None, float | None]:
    """-> (the network size or None, the fovea zoom or None); every flag checked."""
    from sim.cli.common import parse_fovea

    if args.method not in METHODS:
        raise CliError(f"--method {args.method!r}: expected one of {METHODS}")
    if args.tta not in TTA_MODES:
        raise CliError(f"--tta {args.tta!r}: expected one of {TTA_MODES}")
    check_device(args.device)
    if args.method != "bittc" and (args.weights is not None or args.tta != "none" or args.device != "auto"):
        raise CliError(f"--weights / --tta / --device apply to --method bittc, not {args.method!r}")
    size = parse_size(args.size) if args.size is not None else None
    zoom = parse_fovea(args.fovea)
    if zoom is None and args.fovea_center is not None:
        raise CliError("--fovea-center applies with --fovea ZOOM")
    if zoom is not None and size is None:
        raise CliError("--fovea needs --size HxW: the size both views are given to the network at")
    return size, zoom


def _read_views(args, size, zoom) -> tuple[dict, tuple | None]:
    """-> ({'': wide (prev, latest), 'fovea_': fovea (prev, latest)}, the fovea's crop box or None)."""
    import cv2

    prev, latest = read_rgb(args.prev, "PREV"), read_rgb(args.latest, "LATEST")
    if prev.shape != latest.shape:
        raise CliError(
            f"PREV is {prev.shape[0]}x{prev.shape[1]} px but LATEST is "
            f"{latest.shape[0]}x{latest.shape[1]} px: the frames must be the same size"
        )
    views, box = {}, None
    if zoom is not None:
        box = fovea_box(latest.shape[:2], zoom, size, args.fovea_center)
        views["fovea_"] = [crop_view(im, box, size) for im in (prev, latest)]
    if size is not None:
        prev, latest = (cv2.resize(img, size[::-1], interpolation=cv2.INTER_AREA) for img in (prev, latest))
    check_frame_size(latest.shape[:2], args.method, "--size" if size is not None else "PREV and LATEST")
    return {"": (prev, latest), **views}, box


def _predict(est, views: dict, thr: np.ndarray) -> tuple[dict, dict, dict]:
    """-> (the npz arrays, prefix -> (latest image, geofences, TTC) per view, wall times [ms] of the wide view)."""
    from bittc_core.estimator.base import quantize
    from bittc_core.ttc import eta_to_tau

    maps, shown, wall = {"thresholds_s": thr}, {}, {}
    for prefix, (prev, latest) in views.items():
        # the fovea's own estimator state: its frames are another view, not the next frames of a stream
        e = est if not prefix or not hasattr(est, "fork") else est.fork()
        t0 = time.perf_counter()
        geofence = e.geofence(prev, latest, thr)
        t1 = time.perf_counter()
        eta = e.motion_in_depth(prev, latest)  # the same pair: the network reuses its cached features
        if not prefix:
            wall = {"geofence": round((t1 - t0) * 1e3, 3), "continuous": round((time.perf_counter() - t1) * 1e3, 3)}
            maps["quantized"] = quantize(geofence[np.argsort(thr)]).astype(np.int16)
        ttc = eta_to_tau(eta, est.dt_s).astype(np.float32)
        maps |= {f"{prefix}geofence": geofence.astype(np.float32), f"{prefix}eta": eta.astype(np.float32)}
        maps[f"{prefix}ttc_s"] = ttc
        shown[prefix] = (latest, geofence, ttc)
    return maps, shown, wall


def _write(out_dir: Path, maps: dict, shown: dict, thr: np.ndarray, summary: dict) -> list[str]:
    """Every output file under a temporary name, then renamed into ``out_dir``; -> their names."""
    import cv2

    from bittc_core.data.npz_writer import save_npz
    from sim.video import ttc_overlay

    tmp = Path(tempfile.mkdtemp(prefix=".predict-", dir=out_dir))
    try:
        save_npz(tmp / "prediction.npz", maps)
        images = {}
        for prefix, (img, g, t) in shown.items():
            ones = np.ones(t.shape, bool)
            images[f"{prefix}geofence.png"] = geofence_overlay(img, g, thr)
            images[f"{prefix}ttc.png"] = ttc_overlay(img, t, ones, ones.astype(np.int32), 0.5, 0.5)
        for name, img in images.items():
            ok, png = cv2.imencode(".png", cv2.cvtColor(img, cv2.COLOR_RGB2BGR))
            if not ok:
                raise CliError(f"could not encode {name}")
            (tmp / name).write_bytes(png.tobytes())
        (tmp / "prediction.json").write_text(json.dumps(summary, indent=1) + "\n")
        written = [*OUTPUT_FILES, *(n for n in images if n.startswith("fovea_"))]
        for name in written:
            os.replace(tmp / name, out_dir / name)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return written


def _share(geofence: np.ndarray) -> list[float]:
    return [round(float((g > 0.5).mean()), 6) for g in geofence]


def run(args) -> int:
    from bittc_core.estimator import make_estimator
    from bittc_core.estimator.base import as_thresholds

    size, zoom = _check_flags(args)
    if args.latest is None:
        return run_clip(args, size, zoom)
    check_pair_mode(args)
    views, box = _read_views(args, size, zoom)
    kw = {"weights": args.weights} | backend_kwargs(args, args.method)
    est = make_estimator(args.method, device=args.device, **kw, **({"tta": args.tta} if args.method == "bittc" else {}))
    thr = as_thresholds(args.tau or DEFAULT_TAU_S, est.tau_range_s, sorted_=False)
    if len(np.unique(thr)) != len(thr):
        raise CliError(f"--tau {' '.join(f'{t:g}' for t in thr)}: a threshold is given twice")
    out_dir = writable_dir(args.out)  # every check above runs before anything is written
    maps, shown, wall = _predict(est, views, thr)
    latest = views[""][1]
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
        "inside_share": _share(maps["geofence"]),
        "wall_ms": wall,
    }
    if box is not None:
        summary["fovea"] = {"zoom": zoom, "crop_box_px": list(box), "inside_share": _share(maps["fovea_geofence"])}
    written = _write(out_dir, maps, shown, thr, summary)
    print(
        f"{args.method}: {latest.shape[0]}x{latest.shape[1]} px, frame_dt_s {est.dt_s:g} s, "
        f"geofences {wall['geofence']:.1f} ms, continuous {wall['continuous']:.1f} ms"
    )
    for t, share in zip(thr, summary["inside_share"]):
        print(f"  tau <= {t:g} s: {share:.1%} of the pixels inside")
    if box is not None:
        print(f"fovea x{zoom:g}: crop {box} of the native frame")
        for t, share in zip(thr, summary["fovea"]["inside_share"]):
            print(f"  tau <= {t:g} s: {share:.1%} of the fovea's pixels inside")
    print(f"wrote {', '.join(str(out_dir / n) for n in written)}")
    return 0
