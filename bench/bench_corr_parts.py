"""What the correlation volume's added parts cost a job: its shifted correlations
(``cpu-small-corr-shift``), its column correlations (``cpu-small-corr-column``), or those
and the source warped by columns as a second input (``cpu-small-corr-column-input``).

Usage: python bench/bench_corr_parts.py [--config NAME [NAME ...]] [--calls N] [--threads T]
Times the streaming geofence call (one new frame extracted, the reference context, K = 4
thresholds against the cached previous frame) of the wide view (96x288) for the shipped
weights and for the same weights grown into each ``--config`` (default cpu-small-corr-shift;
the added convs start at zero, and what a job costs does not depend on their weights), in
interleaved rounds. Prints the medians [ms] and each one's ratio to the shipped weights';
nothing is asserted.
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

GROWN_CONFIGS = ("cpu-small-corr-shift", "cpu-small-corr-column", "cpu-small-corr-column-input")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--calls", type=int, default=100)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--config", nargs="+", choices=GROWN_CONFIGS, default=GROWN_CONFIGS[:1])
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    thr = default_thresholds(4)
    rng = np.random.default_rng(0)
    frames = [rng.integers(0, 256, (96, 288, 3), dtype=np.uint8) for _ in range(args.calls + 6)]
    configs = list(dict.fromkeys(args.config))
    with tempfile.TemporaryDirectory() as tmp:
        ests = {"cpu-small-corr (shipped)": make_estimator("bittc", device="cpu")}
        for name in configs:
            grown = Path(tmp) / f"{name}.pt"
            save_checkpoint(grown, grown_payload(DEFAULT_WEIGHTS, name))
            ests[name] = make_estimator("bittc", weights=str(grown), device="cpu")
        calls = {name: (lambda a, b, est=est: est.geofence(a, b, thr)) for name, est in ests.items()}
        ms = interleaved_median_ms(calls, frames, warmup=5)
    print(f"streaming K = 4 wide-view geofence calls (96x288), {args.threads} threads, {args.calls} interleaved rounds")
    for name, t in ms.items():
        print(f"{name:>34}: {t:6.2f} ms")
    base = ms["cpu-small-corr (shipped)"]
    for name in configs:
        print(f"{'ratio ' + name:>34}: {ms[name] / base:6.3f} (+{ms[name] - base:.2f} ms)")


if __name__ == "__main__":
    main()
