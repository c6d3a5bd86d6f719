"""`bittc predict CLIP --out DIR`: the geofences of every frame of a video or a folder of frames.

CLIP is a video file (read by OpenCV) or a folder of image frames (sorted by name); its
capture times come from ``--timestamps FILE`` (one per frame: seconds or KITTI's date and
time), ``--fps``, or the video's own frame rate. Each frame is paired with the earlier
one ``frame_dt_s`` x ``--frame-stride`` before it (default 3, as the controller pairs
frames; ``sim.footage``: 30 fps footage pairs frames 9 apart, 3 at stride 1); footage
whose spacing cannot be matched is refused with the reason. TTC counts from each frame's
capture time. Writes into DIR, each file whole or not at all:

* ``overlay.mp4``: every paired frame, the wide view's geofences and the fovea's beside
  it, at the clip's frame rate;
* ``frames.csv``: one row per paired frame: ``frame``, ``t_s``, ``prev_frame``,
  ``pair_dt_s``, the share of pixels inside each fence per view over the whole view
  (``wide_inside_<tau>s``, ``fovea_inside_<tau>s``) and over ``--roi``
  (``wide_roi_inside_<tau>s``, ...; empty where the region misses the view); with
  ``--controller geofence``: ``stage``, ``warning``, ``decel_mps2``, ``fence_fired_s``,
  ``fired_view``, and the ego's motion it was given (``ego_speed_mps``,
  ``ego_yaw_rate_radps``);
* ``prediction.json``: the settings, the clip, the pairing, the views' crops and
  calibrations, the wall time and its ratio to the clip's duration.

Calibration (``--fx --fy --cx --cy`` [native px], or ``--calib`` a KITTI
``calib_cam_to_cam.txt``): the fovea becomes the crop in which a fovea pixel spans the
angle it spans in training (``sim.footage_camera``), centred on the horizon point ahead
(``--pitch``). ``--controller geofence`` runs the geofence controller open loop on the
footage (it needs the calibration and the ego's motion: ``--ego-speed`` constant, or
``--oxts DIR`` a KITTI drive's oxts folder, one file a frame: speed vf and yaw rate wz of
the pair's latest frame). Its persistence and release,
counted in jobs at the simulator's 10 Hz, are scaled to the footage's rate, so they span
the same time.
"""

from __future__ import annotations

import csv
import io
import json
import os
import shutil
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from bittc_core.errors import CliError
from sim.cli.clip_flags import check, intrinsics, views_of
from sim.cli.predict_controller import controller_step, open_loop_controller
from sim.footage_views import crop_view, fence_columns, roi_in_view, side_by_side


@dataclass
class _ClipRun:
    """Everything a clip's frame loop needs, checked before anything is written."""

    args: object
    clip: object
    est: object
    views: dict  # view -> (crop box [native px], (H, W) [px])
    cams: dict  # view -> Intrinsics of the view, or None without a calibration
    stride: int
    pair_dt_s: float
    partner: np.ndarray
    step_s: float
    thr: np.ndarray
    thr_est: np.ndarray
    rois: dict
    ctrl: object = None
    calibration: object = None
    motion: tuple | None = None  # per frame (speed [m/s], yaw rate [rad/s], + left) from --oxts
    first: dict = field(default_factory=lambda: {"warning": None, "brake": None})


def _prepare(args, size, zoom) -> _ClipRun:
    from bittc_core.estimator import make_estimator
    from bittc_core.estimator.base import as_thresholds
    from controllers.geofence import DEFAULT_FRAME_STRIDE, default_thresholds, estimator_thresholds
    from sim.cli.common import backend_kwargs
    from sim.footage import FootageError, open_clip, pair_frames, read_timestamps

    check(args, size, zoom)
    intr = intrinsics(args)
    if args.controller is not None and intr is None:
        raise CliError("--controller geofence needs the camera's calibration: --fx --cx --cy, or --calib FILE")
    try:
        times = read_timestamps(args.timestamps) if args.timestamps is not None else None
        clip = open_clip(args.prev, args.fps, times)
    except FootageError as e:
        raise CliError(f"CLIP: {e}") from None
    views, cams = views_of(args, clip, size, zoom, intr)
    kw = {"weights": args.weights} | backend_kwargs(args, args.method)
    est = make_estimator(args.method, device=args.device, **kw, **({"tta": args.tta} if args.method == "bittc" else {}))
    stride = args.frame_stride or DEFAULT_FRAME_STRIDE
    try:
        partner = pair_frames(clip.times_s, est.dt_s * stride)
    except FootageError as e:
        raise CliError(f"CLIP {args.prev!r}: {e}") from None
    thr_s = args.tau if args.tau is not None else default_thresholds(4)
    thr = as_thresholds(thr_s, (0.0, np.inf), sorted_=False)
    if len(np.unique(thr)) != len(thr):
        raise CliError(f"--tau {' '.join(f'{t:g}' for t in thr)}: a threshold is given twice")
    try:
        thr_est = estimator_thresholds(est, thr, est.dt_s, stride)
    except ValueError as e:
        raise CliError(f"--tau / --frame-stride: {e}") from None
    rois = {v: roi_in_view(args.roi, box, hw) for v, (box, hw) in views.items()}
    step = float(np.median(np.diff(clip.times_s)))
    run = _ClipRun(args, clip, est, views, cams, stride, est.dt_s * stride, partner, step, thr, thr_est, rois)
    if args.oxts is not None:
        from sim.kitti_raw import read_oxts

        try:
            run.motion = read_oxts(args.oxts, len(clip.times_s))
        except FootageError as e:
            raise CliError(f"--oxts {args.oxts!r}: {e}") from None
    if args.controller:
        ratio = max(int(round(est.dt_s / step)), 1)  # jobs per simulator job (10 Hz)
        run.ctrl, run.calibration = open_loop_controller(args, est, thr, views, cams, stride, ratio)
    return run


def _network_step(run: _ClipRun, forks: dict, row: dict, now: dict, before: dict, t_s: float):
    """The network on each view's pair -> (pictures, HUD lines, alert); fills ``row``."""
    from sim.video import threshold_overlay

    pictures = []
    for v in run.views:
        maps = forks[v].geofence(before[v], now[v], run.thr_est)
        fence_columns(row, v, run.thr, maps, run.rois[v], run.args.roi is not None)
        pictures.append(threshold_overlay(now[v], maps, run.thr))
    return pictures, [f"t {t_s:.2f} s  fences {' '.join(f'{t:g}' for t in np.sort(run.thr))} s"], False


def _frame_loop(run: _ClipRun, video) -> list[dict]:
    """Every frame of the clip; each paired one through the network (or the controller), its
    row returned and its picture written to ``video``."""
    from tqdm import tqdm

    from sim.video import hud

    forks = {}  # the network's own cache per view; the controller keeps its own
    if run.ctrl is None:
        forks = {v: (run.est if v == "wide" or not hasattr(run.est, "fork") else run.est.fork()) for v in run.views}
    scale = video.scale_for(run.views["wide"][1][1])
    idx = np.arange(len(run.partner))
    keep_back = int((idx - np.where(run.partner >= 0, run.partner, idx)).max())
    rows, kept = [], {}
    times = run.clip.times_s
    frames = tqdm(run.clip.frames(), total=len(times), unit="frame", desc="predict", disable=None)
    for i, frame in enumerate(frames):
        kept[i] = {v: crop_view(frame, box, hw) for v, (box, hw) in run.views.items()}
        kept.pop(i - keep_back - 1, None)
        j = int(run.partner[i])
        if j < 0:
            continue
        row = {"frame": i, "t_s": round(float(times[i]), 6), "prev_frame": j}
        row["pair_dt_s"] = round(float(times[i] - times[j]), 6)
        if run.ctrl is not None:
            pictures, lines, alert = controller_step(run, row, kept[i], kept[j], float(times[i]), i)
        else:
            pictures, lines, alert = _network_step(run, forks, row, kept[i], kept[j], float(times[i]))
        video.write(hud(side_by_side(pictures, scale), lines, alert))
        rows.append(row)
    return rows


def _summary(run: _ClipRun, rows: list[dict], wall_s: float) -> dict:
    a, clip = run.args, run.clip
    duration = float(clip.times_s[-1] + run.step_s)
    ctrl = None
    if run.ctrl is not None:
        ctrl = {
            "name": "geofence",
            "ego_speed_mps": a.ego_speed,
            "ego_motion": "oxts" if a.oxts is not None else "constant",
            "camera_height_m": a.camera_height,
            "pitch_deg": a.pitch,
            "persistence_jobs": run.ctrl.cfg.persistence_frames,
            "release_jobs": run.ctrl.cfg.release_frames,
            "first_warning_t_s": run.first["warning"],
            "first_brake_t_s": run.first["brake"],
        }
    views = {
        v: {"crop_box_px": list(box), "size_hw": list(hw), "intrinsics_px": _intr_dict(run.cams[v])}
        for v, (box, hw) in run.views.items()
    }
    return {
        "method": a.method,
        "weights": a.weights,
        "backend": a.backend,
        "clip": {"source": clip.source, "kind": clip.kind, "frames": len(clip.times_s), "size_hw": list(clip.size_hw)},
        "duration_s": round(duration, 6),
        "frame_interval_s": round(run.step_s, 6),
        "frame_dt_s": run.est.dt_s,
        "frame_stride": run.stride,
        "pair_dt_s": round(run.pair_dt_s, 6),
        "paired_frames": len(rows),
        "unpaired_frames": int((run.partner < 0).sum()),
        "thresholds_s": run.thr.tolist(),
        "views": views,
        "roi_px": a.roi,
        "controller": ctrl,
        "wall_s": round(wall_s, 3),
        "wall_over_duration": round(wall_s / duration, 3),
    }


def _csv_text(rows: list[dict]) -> str:
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=list(dict.fromkeys(k for r in rows for k in r)), restval="")
    writer.writeheader()
    writer.writerows(rows)
    return buf.getvalue()


def run_clip(args, size, zoom) -> int:
    from sim.cli.common import writable_dir
    from sim.video import VideoWriter

    run = _prepare(args, size, zoom)
    out_dir = writable_dir(args.out)  # every check above runs before anything is written
    tmp = Path(tempfile.mkdtemp(prefix=".predict-", dir=out_dir))
    video = VideoWriter(tmp / "overlay.mp4", 1.0 / run.step_s)
    written = ["overlay.mp4", "frames.csv", "prediction.json"]
    try:
        t0 = time.perf_counter()
        rows = _frame_loop(run, video)
        wall = time.perf_counter() - t0
        video.close()
        (tmp / "frames.csv").write_text(_csv_text(rows))
        summary = _summary(run, rows, wall)
        (tmp / "prediction.json").write_text(json.dumps(summary, indent=1) + "\n")
        for name in written:
            os.replace(tmp / name, out_dir / name)
    except BaseException:
        video.abort()
        raise
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    print(
        f"{args.method}: {len(rows)} of {len(run.clip.times_s)} frames paired {run.pair_dt_s:g} s apart, "
        f"{wall:.1f} s for a {summary['duration_s']:.1f} s clip ({summary['wall_over_duration']:.2f}x)"
    )
    if run.ctrl is not None:
        print(f"  first warning at {run.first['warning']} s, first braking at {run.first['brake']} s")
    print(f"wrote {', '.join(str(out_dir / n) for n in written)}")
    return 0


def _intr_dict(c):
    return None if c is None else {k: round(v, 4) for k, v in vars(c).items()}
