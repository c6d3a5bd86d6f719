"""The closed loop's real-time factor per K, and where a frame's time goes.

Usage: python bench/bench_loop.py [--scenario CCRs-50] [--ks 1 2 4 8 16] [--controller geofence]
                                  [--turn-across on|off|both] [--oncoming on|off|both]

One run per K of the same case with the network-driven controller and ``measured``
latency, all in this process, one after the other: per K, the real-time factor at the
camera's 10 Hz (simulated seconds per wall-clock second of the whole loop), and the
wall time per frame [ms] of rendering, traffic integration (highway-env substeps and
footprint checks), per-actor truth, the per-pixel ground truth that the fence-lag
measurement needs (analysis only: a deployed loop would not compute it), the
estimator and the controller's own logic. ``--turn-across both`` runs each K with the
tracker's turn rules on and off, one after the other, and prints the ratio of the
controller's own time (on / off); ``--oncoming both`` the same for its rules for oncoming
traffic. Prints the figures of this run; asserts nothing. Run it
alone: other jobs on a 2-core CPU inflate every figure.
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
    ap.add_argument("--turn-across", choices=("on", "off", "both"), default="on")
    ap.add_argument("--oncoming", choices=("on", "off", "both"), default="on")
    args = ap.parse_args()
    both = {"on": (True,), "off": (False,), "both": (True, False)}
    rules = [(t, o) for t in both[args.turn_across] for o in both[args.oncoming]]
    case = scenarios.resolve(args.scenario)[0]
    cam = CameraConfig()
    print(f"{args.scenario}, {args.controller}, latency measured, {cam.height_px}x{cam.width_px} at {cam.fps_hz:g} Hz")
    cols = (
        "K",
        "turn",
        "oncoming",
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
    control_ms = {}
    for k, (turn, oncoming) in ((k, r) for k in args.ks for r in rules):
        thr = default_thresholds(k)
        ctrl = controllers.make(args.controller, thresholds_s=thr, turn_across=turn, oncoming=oncoming)
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
        control_ms[k, turn, oncoming] = 1e3 * per[5] / n
        onoff = ["on" if x else "off" for x in (turn, oncoming)]
        print(
            ("{:>9}" * 6).format(k, *onoff, n, len(jobs), sum(r.status == "skipped" for r in loop.records))
            + f"{sim.t_s / wall:>9.2f}{sim.t_s / (wall - gt):>9.2f}"
            + ("{:>9.1f}" * len(per)).format(*(1e3 * x / n for x in per))
        )

    for name, i in (("the turn rules", 0), ("the rules for oncoming traffic", 1)):
        pairs = [(a, b) for a in rules for b in rules if a[i] and not b[i] and a[1 - i] == b[1 - i]]
        for k in args.ks:
            for a, b in pairs:
                on, off = control_ms[(k, *a)], control_ms[(k, *b)]
                ratio = f"{on:.2f} ms a frame with {name}, {off:.2f} without: {on / off:.2f}x"
                print(f"K = {k}: the controller's own logic {ratio}")


if __name__ == "__main__":
    main()
