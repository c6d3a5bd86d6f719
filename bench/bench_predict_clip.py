"""`bittc predict CLIP` on a 10 s, 30 fps, 1242x375 clip: wall time against the clip's duration.

Usage: python bench/bench_predict_clip.py [--scenario benign-light-traffic] [--out runs/bench_clip]
Renders the clip once (``examples/make_clip.py``, kept in --out for the next run), then runs
``bittc predict`` on it three ways, each in its own process, one after the other: the
network alone on the wide view, with the fovea x4 (from the clip's calibration), and the
geofence controller open loop with the fovea, all at K = 4 (the controller's default fences)
and 96x288. Prints each run's wall time (the whole process, start-up included, and the
frame loop alone from prediction.json) and its ratio to the clip's duration. Run it alone:
anything else on the machine inflates the figures.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FENCES = ["0.8", "1.2146", "1.8442", "2.8"]  # the geofence controller's default K = 4


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default="benign-light-traffic")
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--out", default="runs/bench_clip")
    args = ap.parse_args()
    out = Path(args.out)
    clip = out / "clip.mp4"
    if not clip.is_file():
        t0 = time.perf_counter()
        subprocess.run(
            [sys.executable, str(ROOT / "examples/make_clip.py"), "--scenario", args.scenario, "--fps", "30"]
            + ["--seconds", str(args.seconds), "--out", str(out)],
            check=True,
        )
        print(f"rendered {clip} in {time.perf_counter() - t0:.0f} s")
    base = ["bittc", "predict", str(clip), "--size", "96x288", "--tau", *FENCES]
    calib = ["--calib", str(out / "calib_cam_to_cam.txt"), "--pitch", "2"]
    runs = {
        "wide view alone": [*base],
        "wide + fovea x4": [*base, "--fovea", "4", *calib],
        "wide + fovea x4, geofence controller": [*base, "--fovea", "4", *calib, "--controller", "geofence"]
        + ["--ego-speed", "13.89"],
    }
    print(f"{'run':<40}{'process s':>10}{'loop s':>8}{'clip s':>8}{'process / clip':>16}")
    for i, (name, cmd) in enumerate(runs.items()):
        dest = out / f"pred_{i}"
        t0 = time.perf_counter()
        subprocess.run([*cmd, "--out", str(dest)], check=True, capture_output=True)
        wall = time.perf_counter() - t0
        s = json.loads((dest / "prediction.json").read_text())
        print(f"{name:<40}{wall:>10.1f}{s['wall_s']:>8.1f}{s['duration_s']:>8.1f}{wall / s['duration_s']:>16.2f}")


if __name__ == "__main__":
    main()
