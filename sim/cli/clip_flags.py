"""The flags of `bittc predict CLIP` (``sim.cli.predict_clip``): their parsing and checks,
the calibration they give, and the views of the clip they set (crop box and size)."""

from __future__ import annotations

import numpy as np

from bittc_core.errors import CliError

CLIP_ONLY_FLAGS = {
    "fps": "--fps",
    "timestamps": "--timestamps",
    "frame_stride": "--frame-stride",
    "roi": "--roi",
    "controller": "--controller",
    "ego_speed": "--ego-speed",
    "oxts": "--oxts",
    "calib": "--calib",
    "fx": "--fx",
    "fy": "--fy",
    "cx": "--cx",
    "cy": "--cy",
}


def add_clip_flags(p) -> None:
    g = p.add_argument_group("a clip (CLIP alone: a video file or a folder of frames)")
    g.add_argument("--fps", type=float, default=None, help="the clip's frame rate [Hz] (default: the video's own)")
    g.add_argument("--timestamps", default=None, metavar="FILE", help="capture times, one line per frame")
    g.add_argument(
        "--frame-stride",
        type=int,
        default=None,
        metavar="N",
        help="pair frames N x frame_dt_s apart (default 3, as the geofence controller and `bittc eval`)",
    )
    g.add_argument(
        "--roi", type=int, nargs=4, default=None, metavar=("U0", "V0", "U1", "V1"), help="a region [native px]"
    )
    g.add_argument("--controller", default=None, choices=("geofence",), help="run the geofence controller open loop")
    g.add_argument("--ego-speed", type=float, default=None, metavar="MPS", help="the ego's speed [m/s], constant")
    g.add_argument(
        "--oxts",
        default=None,
        metavar="DIR",
        help="the ego's speed and yaw rate per frame from a KITTI drive's oxts folder (vf, wz), one file a frame",
    )
    g.add_argument("--calib", default=None, metavar="FILE", help="a KITTI calib_cam_to_cam.txt (P_rect_02)")
    for name in ("fx", "fy", "cx", "cy"):
        g.add_argument(
            f"--{name}", type=float, default=None, help=f"{name} [native px]" + (" (default fx)" * (name == "fy"))
        )
    g.add_argument("--pitch", type=float, default=0.0, metavar="DEG", help="camera pitch, + down (default 0)")
    g.add_argument("--camera-height", type=float, default=1.3, metavar="M", help="above the ground (default 1.3)")


def check_pair_mode(args) -> None:
    """A pair of image files takes none of the clip's flags."""
    given = [flag for dest, flag in CLIP_ONLY_FLAGS.items() if getattr(args, dest) is not None]
    if given:
        raise CliError(f"{', '.join(given)}: apply to a clip (CLIP alone), not to PREV LATEST")


def intrinsics(args):
    from sim.footage_camera import Intrinsics, read_kitti_calib

    manual = {n: getattr(args, n) for n in ("fx", "fy", "cx", "cy") if getattr(args, n) is not None}
    if args.calib is not None and manual:
        raise CliError(f"--calib and --{' --'.join(manual)}: give one calibration")
    if args.calib is not None:
        return read_kitti_calib(args.calib)
    if not manual:
        return None
    missing = [f"--{n}" for n in ("fx", "cx", "cy") if n not in manual]
    if missing:
        raise CliError(f"{' '.join(missing)}: a calibration needs --fx, --cx and --cy (--fy defaults to --fx)")
    try:
        return Intrinsics(manual["fx"], manual.get("fy", manual["fx"]), manual["cx"], manual["cy"])
    except ValueError as e:  # "fx_px -5: must be > 0" -> "--fx -5: must be > 0"
        raise CliError("--" + str(e).replace("_px", "", 1)) from None


def check(args, size, zoom):
    """The clip's own checks, before anything is read or written."""
    if args.frame_stride is not None and not 1 <= args.frame_stride <= 10:
        raise CliError(f"--frame-stride {args.frame_stride}: must be in [1, 10]")
    if args.fps is not None and args.timestamps is not None:
        raise CliError("--fps and --timestamps: give one")
    if args.fps is not None and not (np.isfinite(args.fps) and args.fps > 0):
        raise CliError(f"--fps {args.fps:g}: must be > 0")
    if args.roi is not None:
        u0, v0, u1, v1 = args.roi
        if u1 <= u0 or v1 <= v0 or min(u0, v0) < 0:
            raise CliError(f"--roi {u0} {v0} {u1} {v1}: needs 0 <= U0 < U1 and 0 <= V0 < V1 [native px]")
    if args.controller is not None:
        if args.ego_speed is not None and args.oxts is not None:
            raise CliError("--ego-speed and --oxts: give one source of the ego's speed")
        if args.oxts is None and (args.ego_speed is None or not (np.isfinite(args.ego_speed) and args.ego_speed >= 0)):
            raise CliError(
                f"--ego-speed {args.ego_speed}: --controller geofence needs the ego's speed >= 0 [m/s] (or --oxts DIR)"
            )
        if args.method != "bittc":
            raise CliError(f"--controller geofence runs the network (--method bittc), not {args.method!r}")
        if size is None:
            raise CliError("--controller geofence needs --size HxW: the network's size")
    elif args.ego_speed is not None or args.oxts is not None:
        flag = "--ego-speed" if args.ego_speed is not None else "--oxts"
        raise CliError(f"{flag} applies with --controller geofence")
    if not (np.isfinite(args.camera_height) and args.camera_height > 0):
        raise CliError(f"--camera-height {args.camera_height:g}: must be > 0 [m]")
    if not -30 <= args.pitch <= 30:
        raise CliError(f"--pitch {args.pitch:g}: must be in [-30, 30] deg")


def views_of(args, clip, size, zoom, intr):
    """-> {view: (crop box [native px], view size (H, W))} and the view's intrinsics (or None)."""
    from sim.cli.common import check_frame_size
    from sim.footage import FootageError
    from sim.footage_camera import fovea_crop, view_intrinsics

    H, W = clip.size_hw
    wide_hw = size or clip.size_hw
    check_frame_size(wide_hw, args.method, "--size" if size else f"the clip's {H}x{W} px frames")
    views = {"wide": ((0, 0, W, H), wide_hw)}
    if zoom is not None:
        if intr is None:
            box, fovea_hw = fovea_box(clip.size_hw, zoom, size, args.fovea_center), size
        else:
            if args.fovea_center is not None:
                raise CliError("--fovea-center: with a calibration the fovea is centred on the horizon point ahead")
            try:
                box, fovea_hw = fovea_crop(clip.size_hw, intr, zoom, size, args.pitch)
            except FootageError as e:
                raise CliError(f"--fovea {args.fovea}: {str(e).split(': ', 1)[1]}") from None
        views["fovea"] = (box, fovea_hw)
    cams = {v: view_intrinsics(intr, box, hw) if intr else None for v, (box, hw) in views.items()}
    return views, cams


def fovea_box(shape_hw, zoom: float, size_hw, center_uv=None) -> tuple[int, int, int, int]:
    """(u0, v0, u1, v1) [native px, u1 and v1 exclusive] of the fovea's crop of a frame of
    ``shape_hw``: (H / zoom) x (W / zoom) pixels centred on ``center_uv`` (default the image
    centre), shifted to lie inside the frame. Refused (CliError) where the crop would hold fewer
    native pixels than ``size_hw`` or the centre lies outside the frame."""
    H, W = shape_hw
    h, w = size_hw
    ch, cw = H / zoom, W / zoom
    if ch < h or cw < w:
        raise CliError(
            f"--fovea {zoom:g}: a {H}x{W} px frame gives a {ch:.0f}x{cw:.0f} px crop, fewer native pixels than "
            f"the network's {h}x{w} (needs frames of at least {zoom * h:.0f}x{zoom * w:.0f} px, or a smaller zoom)"
        )
    u, v = center_uv if center_uv is not None else ((W - 1) / 2, (H - 1) / 2)
    if not (0 <= u <= W - 1 and 0 <= v <= H - 1):
        raise CliError(
            f"--fovea-center {u:g} {v:g}: outside the {W}x{H} px frame (U in [0, {W - 1}], V in [0, {H - 1}])"
        )
    from sim.footage_camera import centred_box

    return centred_box((u, v), (int(round(cw)), int(round(ch))), shape_hw)
