"""What a view costs the network at each size: how much of the fovea's price is fixed?

Usage: python bench/bench_view_size.py [--calls N] [--threads T]
Times the shipped network's streaming geofence call (one new frame extracted, the reference
context, K thresholds against the cached previous frame) on views of several sizes, each
with its own estimator, in interleaved rounds: the wide view at K = 4 (96x288), the fovea's
job at K = 4 (96x144, its two fences from 1.4 s), and smaller views with the same two
fences. A view of an eighth of the wide view's pixels costing most of what the fovea costs
is the fixed part: the network's many small operations. Prints the medians [ms]; nothing
is asserted.
"""

from __future__ import annotations

import argparse

import numpy as np
import torch

from bittc_core.benchmark import interleaved_median_ms
from bittc_core.estimator import make_estimator
from controllers.geofence import default_thresholds

# (height, width) [px], fences of default_thresholds(4) run on it (the largest ones)
SIZES = (((96, 288), 4), ((96, 288), 2), ((96, 144), 2), ((48, 144), 2), ((48, 72), 2), ((96, 144), 1))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--calls", type=int, default=100)
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    base = make_estimator("bittc", device="cpu")
    rng = np.random.default_rng(0)
    thr = default_thresholds(4)
    calls = {}
    for i, (hw, k) in enumerate(SIZES):
        est, frames = base.fork(), [rng.integers(0, 256, (*hw, 3), dtype=np.uint8) for _ in range(args.calls + 6)]
        calls[i] = lambda a, b, est=est, frames=frames, k=k: est.geofence(frames[a], frames[b], thr[-k:])
    ms = interleaved_median_ms(calls, list(range(args.calls + 6)), warmup=5)  # frames by index, each size its own
    print(f"streaming geofence calls, {args.threads} threads, {args.calls} interleaved rounds, shipped weights")
    print(f"{'view [px]':>10}{'fences':>8}{'pixels / wide':>15}{'median ms':>11}")
    wide = SIZES[0][0][0] * SIZES[0][0][1]
    for i, ((h, w), k) in enumerate(SIZES):
        print(f"{h:>4}x{w:<5}{k:>8}{h * w / wide:>15.3f}{ms[i]:>11.2f}")


if __name__ == "__main__":
    main()
