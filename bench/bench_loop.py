"""The closed loop's real-time factor per K, and where a frame's time goes.

Usage: python bench/bench_loop.py [--scenario CCRs-50] [--ks 1 2 4 8 16] [--controller geofence]

One run per K of the same case with the network-driven controller and ``measured``
latency, all in this process, one after the other: per K, the real-time factor at the
camera's 10 Hz (simulated seconds per wall-clock second of the whole loop), and the
wall time per frame [ms] of rendering, traffic integration (highway-env substeps and
footprint checks), per-actor truth, the per-pixel ground truth that the fence-lag
measurement needs (analysis only: a deployed loop would not compute it), the
estimator and the controller's own logic. Prints the figures of this run; asserts
nothing. Run it alone: other jobs on a 2-core CPU inflate every figure.
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import controllers  # noqa: E402
import scenarios  # noqa: E402
from controllers.geofence import default_thresholds  # noqa: E402
from sim.camera import CameraConfig  # noqa: E402
from sim.episode import ScenarioSim  # noqa: E402
from sim.fence_lag import FenceLagMeter  # noqa: E402
from sim.latency import parse_latency  # noqa: E402
from sim.loop import ClosedLoop  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default="CCRs-50")
    ap.add_argument("--ks", type=int, nargs="+", default=[1, 2, 4, 8, 16])
    ap.add_argument("--controller", default="geofence", choices=controllers.ESTIMATOR_CONTROLLERS)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    case = scenarios.resolve(args.scenario)[0]
    cam = CameraConfig()
    print(f"{args.scenario}, {args.controller}, latency measured, {cam.height_px}x{cam.width_px} at {cam.fps_hz:g} Hz")
    cols = (
        "K",
        "frames",
        "jobs",
        "skipped",
        "RTF",
        "RTF_noGT",
        "render",
        "traffic",
        "truth",
        "gt",
        "estimator",
        "control",
        "total",
    )
    print(("{:>9}" * len(cols)).format(*cols) + "   (ms per frame)")
    for k in args.ks:
        ctrl = controllers.make(args.controller, thresholds_s=default_thresholds(k))
        sim = ScenarioSim(case, cam, args.seed, render=True)
        loop = ClosedLoop(
            sim,
            parse_latency("measured"),
            num_alphas=k,
            pairs=True,
            frame_stride=ctrl.frame_stride,
            lag_meter=FenceLagMeter(),
        )
        t0 = time.perf_counter()
        loop.drive(ctrl)
        wall = time.perf_counter() - t0
        sim.close()
        jobs = loop.processed
        est_s = sum(r.decided.telemetry["estimator_ms"] for r in jobs) * 1e-3
        n = len(loop.records)
        tm = loop.timing
        gt = tm.get("ground_truth_s", 0.0)
        per = [tm["render_s"], tm["traffic_s"], tm["truth_s"], gt, est_s, tm["controller_s"] - est_s, wall]
        print(
            ("{:>9}" * 4).format(k, n, len(jobs), sum(r.status == "skipped" for r in loop.records))
            + f"{sim.t_s / wall:>9.2f}{sim.t_s / (wall - gt):>9.2f}"
            + ("{:>9.1f}" * len(per)).format(*(1e3 * x / n for x in per))
        )


if __name__ == "__main__":
    main()
