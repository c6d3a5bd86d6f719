"""The geofence controller's levers, measured: frame stride, persistence, nested fences.

Usage: python docs/controller_levers.py [--cases CCRs benign-oncoming-truck ...]

Runs the shipped network's geofence controller (K = 4, ``fixed:20`` latency so the runs
repeat) on every case for each setting and prints threats avoided, false alarms and the
median fence lag per threshold over the threat runs. Figures in docs/closed_loop.md.
"""

from __future__ import annotations

import argparse
import os
import statistics

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import scenarios  # noqa: E402
from bittc_core.estimator import make_estimator  # noqa: E402
from controllers.geofence import GeofenceConfig, GeofenceController, default_thresholds  # noqa: E402
from sim.camera import CameraConfig  # noqa: E402
from sim.latency import parse_latency  # noqa: E402
from sim.runner import run_case  # noqa: E402

SETTINGS = {  # name -> GeofenceConfig overrides
    "as shipped (stride 3, persistence 2, nested)": {},
    "stride 1": {"frame_stride": 1},
    "stride 2": {"frame_stride": 2},
    "persistence 1": {"persistence_frames": 1},
    "persistence 3": {"persistence_frames": 3},
    "not nested": {"nested": False},
}
DEFAULT_CASES = [
    "CCRs",
    "CCRm",
    "CCRb",
    "cut-in",
    "benign-oncoming-truck",
    "benign-stationary-adjacent",
    "benign-free-road",
    "benign-parked-truck",
    "benign-follow-same-speed",
]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", nargs="+", default=DEFAULT_CASES)
    args = ap.parse_args()
    cases = [c for n in args.cases for c in scenarios.resolve(n)]
    est = make_estimator("bittc")
    thr = default_thresholds(4)
    print(f"{len(cases)} cases: {', '.join(args.cases)}; K = 4 ({', '.join(f'{t:g}' for t in thr)} s), fixed:20")
    print(f"{'setting':<46}{'avoided':>9}{'false alarms':>14}   median fence lag [s] per threshold")
    for name, kw in SETTINGS.items():
        ctrl = GeofenceController(est, GeofenceConfig(thresholds_s=thr, **kw))
        runs = [run_case(c, ctrl, CameraConfig(), 0, latency=parse_latency("fixed:20")) for c in cases]
        threats = [s for s in runs if s["threat"]]
        benign = [s for s in runs if not s["threat"]]
        lags = []
        for t in thr:
            v = [s["fence_lag_s"][f"{t:g}"] for s in threats if s["fence_lag_s"].get(f"{t:g}") is not None]
            lags.append(f"{statistics.median(v):.2f}" if v else "-")
        print(
            f"{name:<46}{sum(not s['collision'] for s in threats):>5}/{len(threats):<3}"
            f"{sum(s['false_alarm'] for s in benign):>10}/{len(benign):<3}   {' / '.join(lags)}"
        )


if __name__ == "__main__":
    main()
