"""Render the README picture: one ego-camera frame, raw and with its exact TTC overlay.

Usage: python docs/make_frame.py [--scenario CCRm-60] [--t 6.0] [--out docs/frame_ttc.png]
"""

from __future__ import annotations

import argparse
import os

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

import cv2  # noqa: E402
import numpy as np  # noqa: E402

import scenarios  # noqa: E402
from sim.camera import CameraConfig  # noqa: E402
from sim.episode import ScenarioSim  # noqa: E402
from sim.video import TTC_MAX_S, ttc_overlay  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenario", default="CCRm-60")
    ap.add_argument("--t", type=float, default=6.0, help="capture time [s]")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default="docs/frame_ttc.png")
    args = ap.parse_args()
    cam = CameraConfig(height_px=192, width_px=576, supersample=2)
    sim = ScenarioSim(scenarios.resolve(args.scenario)[0], cam, seed=args.seed, render=True)
    sim.reset()
    prev = frame = sim.capture()
    while sim.t_s < args.t - 1e-9:
        for _ in range(sim.n_sub):
            sim.substep(0.0)
        prev, frame = frame, sim.capture()
    gt = sim.ground_truth(prev, frame)
    sim.close()
    over = ttc_overlay(frame.image, gt.tau_s, gt.valid, gt.instance)
    label = np.full((22, cam.width_px, 3), 255, np.uint8)
    cv2.putText(
        label,
        f"exact TTC overlay: red 0 s -> green {TTC_MAX_S:g} s (static ground: tau = Z / v_ego)",
        (6, 15),
        cv2.FONT_HERSHEY_SIMPLEX,
        0.42,
        (0, 0, 0),
        1,
        cv2.LINE_AA,
    )
    img = np.vstack([frame.image, over, label])
    tmp = args.out + ".tmp.png"
    cv2.imwrite(tmp, cv2.cvtColor(img, cv2.COLOR_RGB2BGR))
    os.replace(tmp, args.out)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
