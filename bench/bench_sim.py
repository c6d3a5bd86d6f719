"""Simulator speed: render + exact ground truth per frame, and the real-time factor.

Usage: python bench/bench_sim.py [--frames N] [--size HxW] [--supersample S] [--fovea ZOOM]
Prints the figures measured in this run (nothing is asserted). Targets on a 2-core CPU:
render + ground truth <= 15 ms per frame at 96x288; with a fovea, both views rendered
with the ground truth of both <= 2.2x the wide view alone. The two cameras run the same
case side by side, frame by frame in turn, so a slow spell lands on both alike.
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


def _frame_ms(sim, prev):
    """One frame of ``sim``: (traffic, render of every view, ground truth of every view) [ms], the frame."""
    t0 = time.perf_counter()
    for _ in range(sim.n_sub):
        sim.substep(0.0)
    t1 = time.perf_counter()
    frame = sim.capture()
    t2 = time.perf_counter()
    for view in sim.camera.view_names:
        sim.ground_truth(prev, frame, view)
    t3 = time.perf_counter()
    return ((t1 - t0) * 1e3, (t2 - t1) * 1e3, (t3 - t2) * 1e3), frame


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=100)
    ap.add_argument("--size", default="96x288")
    ap.add_argument("--supersample", type=int, default=1)
    ap.add_argument("--scenario", default="benign-free-road")
    ap.add_argument("--fovea", type=float, default=4.0, help="zoom of the second camera's fovea (default 4)")
    args = ap.parse_args()
    h, w = (int(v) for v in args.size.split("x"))
    cams = {
        "wide": CameraConfig(height_px=h, width_px=w, supersample=args.supersample),
        f"wide + fovea x{args.fovea:g}": CameraConfig(
            height_px=h, width_px=w, supersample=args.supersample, fovea_zoom=args.fovea
        ),
    }
    case = scenarios.resolve(args.scenario)[0]
    sims = {k: ScenarioSim(case, cam, seed=0, render=True) for k, cam in cams.items()}
    prev = {}
    for k, sim in sims.items():
        sim.reset()
        prev[k] = sim.capture()
    times = {k: [] for k in sims}
    for _ in range(args.frames):
        for k, sim in sims.items():
            t, prev[k] = _frame_ms(sim, prev[k])
            times[k].append(t)
    for sim in sims.values():
        sim.close()
    med = statistics.median
    print(
        f"scenario {args.scenario}, camera {h}x{w} (supersample {args.supersample}), {args.frames} frames, "
        f"{len(case.actors) + case.traffic} vehicles, torch-free, 1 process, the two cameras in turn"
    )
    frame = {}
    for k, ts in times.items():
        traffic, render, gt = (med(x) for x in zip(*ts))
        frame[k] = med([r + g for _, r, g in ts])
        step_ms = med([sum(t) for t in ts])
        print(f"{k}:")
        print(f"  render           {render:7.2f} ms/frame (median)")
        print(f"  ground truth     {gt:7.2f} ms/frame")
        print(f"  render + GT      {frame[k]:7.2f} ms/frame")
        print(f"  traffic ({sims[k].n_sub} substeps) {traffic:5.2f} ms/frame")
        print(f"  real-time factor {1000.0 / cams[k].fps_hz / step_ms:7.1f} x  (simulated / wall time)")
    wide, both = frame.values()
    print(f"render + GT, wide alone: {wide:.2f} ms (target <= 15 ms at 96x288: {'met' if wide <= 15 else 'NOT met'})")
    ratio = both / wide
    print(f"both views over the wide view: {ratio:.2f}x (target <= 2.2x: {'met' if ratio <= 2.2 else 'NOT met'})")


if __name__ == "__main__":
    main()
