"""Render a KITTI-like frame pair (375 x 1242 px, 0.1 s apart) of a bundled case, for `bittc predict`.

Usage: python examples/make_kitti_like_pair.py [--scenario CCRs-70] [--t 3.2] [--out runs/pair]
Writes PREV.png and LATEST.png (the frames at t - 0.1 s and t) and truth.json (the critical
actor's exact camera-plane TTC at t, from the simulator's ground truth). The camera has
KITTI's image size and a 29 deg vertical field of view (KITTI's colour cameras: fx ~ 721 px).
Then, for the wide view and a x3.9 fovea around the image centre::

    bittc predict runs/pair/PREV.png runs/pair/LATEST.png --size 96x288 --fovea 3.9 --out runs/pred
"""

from __future__ import annotations

import argparse
import json
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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default="CCRs-70")
    ap.add_argument("--t", type=float, default=3.2, help="capture time of LATEST [s]")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default="runs/pair")
    args = ap.parse_args()
    cam = CameraConfig(height_px=KITTI_HW[0], width_px=KITTI_HW[1], vfov_deg=KITTI_VFOV_DEG)
    sim = ScenarioSim(scenarios.resolve(args.scenario)[0], cam, seed=args.seed, render=True)
    try:
        sim.reset()
        frames = []
        while sim.t_s < args.t - 1e-9:
            for _ in range(sim.n_sub):
                sim.substep(0.0)
            if sim.t_s >= args.t - cam.dt_s - 1e-9:
                frames.append(sim.capture())
        prev, latest = frames[-2], frames[-1]
        gt = sim.ground_truth(prev, latest)
        crit = sim.truth().critical
    finally:
        sim.close()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for name, f in (("PREV.png", prev), ("LATEST.png", latest)):
        cv2.imwrite(str(out / name), cv2.cvtColor(f.image, cv2.COLOR_RGB2BGR))
    truth = {"scenario": args.scenario, "t_s": round(latest.t_s, 3), "size_hw": list(KITTI_HW)}
    if crit is not None:
        pix = (gt.instance == crit.instance) & gt.valid
        truth["critical_camera_plane_ttc_s"] = round(float(np.median(gt.tau_s[pix])), 3) if pix.any() else None
        truth["critical_pixels"] = int(pix.sum())
    (out / "truth.json").write_text(json.dumps(truth, indent=1) + "\n")
    print(f"wrote {out}/PREV.png, LATEST.png, truth.json: {truth}")


if __name__ == "__main__":
    main()
