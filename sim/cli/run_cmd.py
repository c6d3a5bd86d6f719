"""`bittc run SCENARIO --controller NAME --out DIR`: one scenario (or sweep), closed loop."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import scenarios
from bittc_core.errors import CliError
from sim.camera import DEFAULT_FOVEA_WIDTH_SHARE, CameraConfig
from sim.cli.common import (
    add_fovea_flag,
    add_seed_flag,
    check_seed,
    parse_fovea,
    parse_size,
    texture_style,
    writable_dir,
)
from sim.cli.loop_flags import add_controller_flags, controller_from_args


def add_parser(sub) -> argparse.ArgumentParser:
    p = sub.add_parser(
        "run",
        help="run a scenario closed loop with a braking controller",
        description="Run a bundled scenario (name, family or case) or a YAML file with a controller. "
        "One case writes DIR/summary.json, trace.csv, config.yaml (and camera.mp4); a sweep writes one "
        "such folder per case plus DIR/summary.csv.",
    )
    p.add_argument("scenario", help="bundled name (see `bittc scenarios`) or path to a YAML file")
    add_controller_flags(p)
    p.add_argument("--out", required=True, help="output directory")
    add_seed_flag(p, "scenery/appearance/traffic seed")
    p.add_argument("--video", action="store_true", help="also write camera.mp4 with the exact TTC overlay and a HUD")
    p.add_argument(
        "--export-kitti",
        default=None,
        metavar="DIR",
        help="also write the run in the KITTI raw layout into DIR (new or empty): 375x1242 image_02 (the wide "
        "view's horizontal field of view), a 64-beam velodyne scan ray-cast from the exact depth, calib, "
        "timestamps, oxts and bittc_truth.csv (one case only; with --realism the images go through the sensor)",
    )
    add_realism_flag(p)
    add_camera_flags(p)
    return p


def add_realism_flag(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--realism",
        action="store_true",
        help="the camera's images go through a sensor drawn from --seed (sim.sensor: rolling shutter and motion "
        "blur from the exact motion, defocus, vignetting, exposure, noise, tone curve, JPEG or H.264-like video); "
        "printed",
    )


def sensor_from_args(args):
    """``--realism`` -> the ``sim.sensor.SensorEffects`` drawn from ``--seed`` (printed), else None."""
    if not args.realism:
        return None
    import numpy as np

    from sim.sensor import REALISM_STREAM, RUN_EFFECTS_WORD, draw_effects

    sensor = draw_effects(np.random.default_rng([args.seed, REALISM_STREAM, RUN_EFFECTS_WORD]))
    print(f"sensor: {json.dumps(sensor.as_dict())}")
    return sensor


def add_camera_flags(p: argparse.ArgumentParser) -> None:
    p.add_argument("--size", default=None, help="camera HxW in px (default 96x288)")
    p.add_argument("--fps", type=float, default=None, help="camera frame rate [Hz] (default 10)")
    p.add_argument("--vfov", type=float, default=None, help="vertical field of view [deg] (default 30)")
    p.add_argument("--pitch", type=float, default=None, help="camera pitch, positive looks down [deg] (default 2)")
    p.add_argument("--camera-height", type=float, default=None, help="camera height above ground [m] (default 1.3)")
    p.add_argument(
        "--jitter-deg", type=float, default=None, help="std of per-frame pitch/yaw/roll jitter [deg] (default 0)"
    )
    p.add_argument("--supersample", type=int, default=None, help="anti-aliasing factor 1-4 (default 1)")
    add_fovea_flag(p)
    p.add_argument(
        "--fovea-width",
        type=float,
        default=None,
        metavar="SHARE",
        help=f"the fovea's width over the wide view's, in (0, 1] (default {DEFAULT_FOVEA_WIDTH_SHARE:g})",
    )
    p.add_argument(
        "--ground-texture",
        default="detailed",
        help="road and verges: detailed (default) or smooth (as in dataset bittc_v1)",
    )
    p.add_argument(
        "--vehicle-texture",
        default="plain",
        help="vehicle paint and glass: plain (default, as in datasets bittc_v1 and bittc_v2), detailed "
        "(as in bittc_v3), mixed (half the texture variants of each colour detailed, as in bittc_v5 and bittc_v6), "
        "dressed (detailed, windows in frames, number plates and lamps) or assorted (a third each plain, detailed, "
        "dressed)",
    )


def textures_from_args(args):
    return texture_style(args.ground_texture, args.vehicle_texture)


def camera_from_args(args) -> CameraConfig:
    kw = {}
    for flag, field in (
        ("vfov", "vfov_deg"),
        ("pitch", "pitch_deg"),
        ("camera_height", "mount_height_m"),
        ("jitter_deg", "jitter_deg"),
        ("supersample", "supersample"),
        ("fovea_width", "fovea_width_share"),
    ):
        if getattr(args, flag) is not None:
            kw[field] = getattr(args, flag)
    if args.size is not None:
        kw["height_px"], kw["width_px"] = parse_size(args.size)
    if args.fps is not None:
        if not 1.0 <= args.fps <= 100.0:
            raise CliError(f"--fps {args.fps}: must be in [1, 100] Hz")
        kw["fps_hz"] = args.fps
    kw["fovea_zoom"] = parse_fovea(args.fovea)
    try:
        return CameraConfig(**kw)
    except ValueError as e:
        raise CliError(str(e)) from None


def run(args) -> int:
    from sim.runner import run_case
    from sim.suite import format_table, run_cases

    check_seed(args.seed)
    camera = camera_from_args(args)
    textures = textures_from_args(args)
    cases = scenarios.resolve(args.scenario)
    controller, latency = controller_from_args(args, camera)
    export = _export_dir(args.export_kitti, cases)
    sensor = sensor_from_args(args)
    out = writable_dir(args.out)
    kw = {"textures": textures, "latency": latency, "sensor": sensor}
    if len(cases) == 1:
        s = run_case(cases[0], controller, camera, args.seed, out, video=args.video, export_kitti=export, **kw)
        print(json.dumps(s, indent=2))
    else:
        summaries = run_cases(cases, controller, camera, args.seed, out, video=args.video, **kw)
        print(format_table(summaries))
    print(f"wrote {Path(out)}")
    return 0


def _export_dir(path: str | None, cases) -> Path | None:
    if path is None:
        return None
    if len(cases) != 1:
        raise CliError(f"--export-kitti {path!r}: exports one case; {len(cases)} were given")
    p = Path(path)
    if p.exists() and (not p.is_dir() or any(p.iterdir())):
        raise CliError(f"--export-kitti {path!r}: exists and is not an empty folder")
    return p
