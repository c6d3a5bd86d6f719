"""Simulator speed: render + exact ground truth per frame, and the real-time factor.

Usage: python bench/bench_sim.py [--frames N] [--size HxW] [--supersample S]
Prints the figures measured in this run (nothing is asserted). Target on a 2-core CPU:
render + ground truth <= 15 ms per frame at 96x288.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

import scenarios  # noqa: E402
from sim.camera import CameraConfig  # noqa: E402
from sim.episode import ScenarioSim  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=100)
    ap.add_argument("--size", default="96x288")
    ap.add_argument("--supersample", type=int, default=1)
    ap.add_argument("--scenario", default="benign-free-road")
    args = ap.parse_args()
    h, w = (int(v) for v in args.size.split("x"))
    cam = CameraConfig(height_px=h, width_px=w, supersample=args.supersample)
    case = scenarios.resolve(args.scenario)[0]
    sim = ScenarioSim(case, cam, seed=0, render=True)
    sim.reset()
    prev = sim.capture()
    render_ms, gt_ms, traffic_ms = [], [], []
    for _ in range(args.frames):
        t0 = time.perf_counter()
        for _ in range(sim.n_sub):
            sim.substep(0.0)
        t1 = time.perf_counter()
        frame = sim.capture()
        t2 = time.perf_counter()
        sim.ground_truth(prev, frame)
        t3 = time.perf_counter()
        traffic_ms.append((t1 - t0) * 1e3)
        render_ms.append((t2 - t1) * 1e3)
        gt_ms.append((t3 - t2) * 1e3)
        prev = frame
    sim.close()
    med = statistics.median
    frame_ms = med([r + g for r, g in zip(render_ms, gt_ms)])
    step_ms = med([r + g + t for r, g, t in zip(render_ms, gt_ms, traffic_ms)])
    print(
        f"scenario {args.scenario}, camera {h}x{w} (supersample {args.supersample}), {args.frames} frames, "
        f"{len(case.actors) + case.traffic} vehicles, torch-free, 1 process"
    )
    print(f"render           {med(render_ms):7.2f} ms/frame (median)")
    print(f"ground truth     {med(gt_ms):7.2f} ms/frame")
    print(
        f"render + GT      {frame_ms:7.2f} ms/frame   "
        f"(target <= 15 ms at 96x288: {'met' if frame_ms <= 15 else 'NOT met'})"
    )
    print(f"traffic (10 substeps) {med(traffic_ms):5.2f} ms/frame")
    print(f"real-time factor {1000.0 / cam.fps_hz / step_ms:7.1f} x  (simulated time / wall time at {cam.fps_hz:g} Hz)")


if __name__ == "__main__":
    main()
