"""What the correlation volume's added parts cost a job: its shifted correlations
(``cpu-small-corr-shift``) or its column correlations (``cpu-small-corr-column``).

Usage: python bench/bench_corr_parts.py [--config NAME] [--calls N] [--threads T]
Times the streaming geofence call (one new frame extracted, the reference context, K = 4
thresholds against the cached previous frame) of the wide view (96x288) for the shipped
weights and for the same weights grown into ``--config`` (default cpu-small-corr-shift;
its added convs start at zero, and what a job costs does not depend on their weights), in
interleaved rounds. Prints the medians [ms] and their ratio; nothing is asserted.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np
import torch

from bittc_core.benchmark import interleaved_median_ms
from bittc_core.checkpoint import DEFAULT_WEIGHTS, save_checkpoint
from bittc_core.checkpoint_ops import grown_payload
from bittc_core.estimator import make_estimator
from controllers.geofence import default_thresholds

GROWN_CONFIGS = ("cpu-small-corr-shift", "cpu-small-corr-column")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--calls", type=int, default=100)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--config", choices=GROWN_CONFIGS, default=GROWN_CONFIGS[0])
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    thr = default_thresholds(4)
    rng = np.random.default_rng(0)
    frames = [rng.integers(0, 256, (96, 288, 3), dtype=np.uint8) for _ in range(args.calls + 6)]
    with tempfile.TemporaryDirectory() as tmp:
        grown = Path(tmp) / "grown.pt"
        save_checkpoint(grown, grown_payload(DEFAULT_WEIGHTS, args.config))
        ests = {
            "cpu-small-corr (shipped)": make_estimator("bittc", device="cpu"),
            args.config: make_estimator("bittc", weights=str(grown), device="cpu"),
        }
        calls = {name: (lambda a, b, est=est: est.geofence(a, b, thr)) for name, est in ests.items()}
        ms = interleaved_median_ms(calls, frames, warmup=5)
    print(f"streaming K = 4 wide-view geofence calls (96x288), {args.threads} threads, {args.calls} interleaved rounds")
    for name, t in ms.items():
        print(f"{name:>26}: {t:6.2f} ms")
    base, grown_ms = ms["cpu-small-corr (shipped)"], ms[args.config]
    print(f"{'ratio':>26}: {grown_ms / base:6.3f} (+{grown_ms - base:.2f} ms)")


if __name__ == "__main__":
    main()
