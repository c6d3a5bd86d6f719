"""Render a KITTI-like clip (375 x 1242 px) of a bundled case, for `bittc predict CLIP`.

Usage: python examples/make_clip.py [--scenario CCRs-50] [--fps 30] [--seconds 10] [--out runs/clip]
Writes clip.mp4 (or, with --frames, frames/000000.png ...), timestamps.txt (one capture time
[s] per frame), calib_cam_to_cam.txt (the camera's P_rect_02, in KITTI's format) and
truth.csv (per frame: the critical actor's exact bumper-to-bumper TTC [s] from the simulator's
ground truth, empty when there is none). The camera has KITTI's image size and a 29 deg
vertical field of view (fx ~ 721 px), 1.3 m above the road, pitched 2 deg down. The ego
keeps its speed (no braking) until it touches the target. Then::

    bittc predict runs/clip/clip.mp4 --size 96x288 --fovea 4 --calib runs/clip/calib_cam_to_cam.txt \\
        --pitch 2 --controller geofence --ego-speed 13.89 --out runs/clip_pred
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

import cv2  # noqa: E402
import numpy as np  # noqa: E402

import scenarios  # noqa: E402
from sim.camera import CameraConfig  # noqa: E402
from sim.episode import ScenarioSim  # noqa: E402

KITTI_HW = (375, 1242)  # [px]
KITTI_VFOV_DEG = 29.0  # [deg] 2 atan(187.5 / 721)


def calib_text(cam: CameraConfig) -> str:
    fx, fy, cx, cy = cam.intrinsics()
    p = f"{fx:.6e} 0.000000e+00 {cx:.6e} 0.000000e+00 0.000000e+00 {fy:.6e} {cy:.6e} 0.000000e+00 "
    p += "0.000000e+00 0.000000e+00 1.000000e+00 0.000000e+00"
    return f"calib_time: rendered by bittc-sim\nP_rect_02: {p}\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default="CCRs-50")
    ap.add_argument("--fps", type=float, default=30.0)
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--frames", action="store_true", help="a folder of PNG frames instead of an mp4")
    ap.add_argument("--out", default="runs/clip")
    args = ap.parse_args()
    cam = CameraConfig(height_px=KITTI_HW[0], width_px=KITTI_HW[1], vfov_deg=KITTI_VFOV_DEG, fps_hz=args.fps)
    out = Path(args.out)
    (out / "frames" if args.frames else out).mkdir(parents=True, exist_ok=True)
    writer = None
    if not args.frames:
        writer = cv2.VideoWriter(str(out / "clip.mp4"), cv2.VideoWriter_fourcc(*"mp4v"), args.fps, KITTI_HW[::-1])
    times, ttc = [], []
    sim = ScenarioSim(scenarios.resolve(args.scenario)[0], cam, seed=args.seed, render=True)
    try:
        truth = sim.reset()
        for i in range(int(round(args.seconds * args.fps))):
            if i:
                for _ in range(sim.n_sub):
                    sim.substep(0.0)
                truth = sim.truth()
            frame = sim.capture()
            bgr = cv2.cvtColor(frame.image, cv2.COLOR_RGB2BGR)
            if writer is not None:
                writer.write(bgr)
            else:
                cv2.imwrite(str(out / "frames" / f"{i:06d}.png"), bgr)
            times.append(frame.t_s)
            crit = truth.critical
            ttc.append("" if crit is None or not np.isfinite(crit.ttc_s) else f"{crit.ttc_s:.4f}")
            if sim.collision is not None:
                break
    finally:
        sim.close()
        if writer is not None:
            writer.release()
    (out / "timestamps.txt").write_text("".join(f"{t:.6f}\n" for t in times))
    (out / "calib_cam_to_cam.txt").write_text(calib_text(cam))
    (out / "truth.csv").write_text(
        "frame,t_s,critical_ttc_s\n" + "".join(f"{i},{t:.6f},{v}\n" for i, (t, v) in enumerate(zip(times, ttc)))
    )
    print(f"wrote {len(times)} frames ({args.fps:g} fps) of {args.scenario} to {out}")


if __name__ == "__main__":
    main()
