"""`bittc generate`: randomised synthetic TTC data (see bittc_core/data/format.py)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from bittc_core.errors import ConfigError
from sim.cli.common import add_seed_flag, check_seed, flag_error, parse_size

#: the fields of ``GenerationConfig`` and ``generate`` -> their flags
_FLAGS = {
    "seed": "--seed",
    "clip_length": "--clip-length",
    "fps_hz": "--fps",
    "ahead_share": "--ahead-share",
    "fovea_share": "--fovea-share",
    "realism_share": "--realism-share",
    "realism_codecs": "--realism-codecs",
    "vru_share": "--vru-share",
    "supersample": "--supersample",
    "ground_texture": "--ground-texture",
    "vehicle_texture": "--vehicle-texture",
    "split": "--split",
    "samples": "--samples",
    "workers": "--workers",
    "backend": "--backend",
    "ray_address": "--ray-address",
    "output folder": "--out",
}


def add_parser(sub) -> argparse.ArgumentParser:
    p = sub.add_parser(
        "generate",
        help="generate synthetic TTC training data",
        description="Render randomised scenes with exact ground truth into DIR/SPLIT/. Re-running skips "
        "finished samples and regenerates damaged ones; the manifest and dataset card are rebuilt.",
    )
    p.add_argument("--out", required=True, help="dataset directory")
    p.add_argument("--samples", type=int, required=True, help="samples in this split (indices 0..N-1)")
    add_seed_flag(p, "dataset seed", default=None)
    p.add_argument("--split", default="train", choices=["train", "val", "test"], help="split (disjoint seed ranges)")
    p.add_argument("--size", default="96x288", help="HxW in px (default 96x288)")
    p.add_argument("--fps", type=float, default=10.0, help="frame rate [Hz] (default 10)")
    p.add_argument("--clip-length", type=int, default=2, help="frames per sample (default 2: previous and latest)")
    p.add_argument("--supersample", type=int, default=1, help="anti-aliasing factor (1-4, default 1)")
    p.add_argument(
        "--ground-texture",
        default="detailed",
        help="road and verge textures: detailed (default; patches and broadband noise whose motion "
        "can be measured) or smooth (as in datasets made before the option, e.g. bittc_v1)",
    )
    p.add_argument(
        "--vehicle-texture",
        default="plain",
        help="vehicle paint and glass: plain (default, as in bittc_v1 and bittc_v2), detailed (shading "
        "and spots inside the outline whose motion can be measured, as in bittc_v3), mixed (half the "
        "texture variants of each colour plain, half detailed, as in bittc_v5), dressed (detailed, windows in "
        "frames, number plates and lamps) or assorted (a third each plain, detailed and dressed)",
    )
    p.add_argument(
        "--ahead-share",
        type=float,
        default=0.0,
        metavar="SHARE",
        help="this share of the samples has a braking case ahead: a GVT, car, van or truck in or near "
        "the ego's lane (overlap 25-100 %% on either side), stationary, slower or braking, at 0.3-4 s TTC, ego "
        "10-130 km/h, beside the random scene (default 0: random scenes only, as in bittc_v1-v3)",
    )
    p.add_argument(
        "--fovea-share",
        type=float,
        default=0.0,
        metavar="SHARE",
        help="this share of the samples is seen as a fovea sees it: 5-16 deg vertical field of view centred on "
        "the horizon point ahead, a GVT, car, van or truck in or near the ego's lane 15-150 m ahead (stationary, "
        "slower or braking at 0.3-4 s TTC, or a lead at the ego's speed or pulling away), adjacent-lane and "
        "oncoming vehicles, ego 10-130 km/h (default 0: none, as in bittc_v1-v4)",
    )
    p.add_argument(
        "--realism-share",
        type=float,
        default=0.0,
        metavar="SHARE",
        help="this share of the samples goes through a camera sensor drawn per clip (sim.sensor): rolling shutter "
        "and motion blur from the exact motion, defocus, vignetting, exposure, shot and read noise, tone curve, "
        "JPEG or an H.264-like video stream (default 0: clean renders, as in every dataset the shipped weights were "
        "trained on)",
    )
    p.add_argument(
        "--realism-codecs",
        default="jpeg+video",
        choices=("jpeg", "video", "jpeg+video"),
        help="the compressions the sensor draws from, half the clips compressed (default jpeg+video; jpeg: the "
        "draws of the datasets made before the video codec)",
    )
    p.add_argument(
        "--vru-share",
        type=float,
        default=0.0,
        metavar="SHARE",
        help="this share of the samples has pedestrians (adult, child) and cyclists crossing, walking or riding "
        "along, near and far, on a road with sidewalks, ego 0-70 km/h (default 0: none, as in bittc_v1-v7)",
    )
    p.add_argument("--workers", type=int, default=1, help="parallel worker processes or Ray tasks (default 1)")
    p.add_argument("--backend", default="local", choices=("local", "ray"), help="local (process pool, default) or ray")
    p.add_argument(
        "--ray-address", default=None, help="address of an existing Ray cluster (default: start a local one)"
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    return p


def run(args) -> int:
    h, w = parse_size(args.size)
    check_seed(args.seed)
    try:
        stats = _generate(args, h, w)
    except ConfigError as e:
        raise flag_error(e, _FLAGS) from None
    print(json.dumps(stats))
    return 0


def _generate(args, h: int, w: int) -> dict:
    from sim.datagen.generate import GenerationConfig, generate

    cfg = GenerationConfig(
        seed=args.seed,
        height_px=h,
        width_px=w,
        fps_hz=args.fps,
        clip_length=args.clip_length,
        supersample=args.supersample,
        ground_texture=args.ground_texture,
        vehicle_texture=args.vehicle_texture,
        ahead_share=args.ahead_share,
        fovea_share=args.fovea_share,
        realism_share=args.realism_share,
        realism_codecs=args.realism_codecs,
        vru_share=args.vru_share,
    )
    return generate(
        Path(args.out),
        cfg,
        args.split,
        args.samples,
        args.workers,
        args.backend,
        args.ray_address,
        progress=not args.no_progress,
    )
