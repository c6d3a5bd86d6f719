"""Two views of one frame through the network: one batched forward pass or two passes?

Usage: python bench/bench_fovea_batch.py [--calls N] [--thresholds K] [--threads T]
Times, in interleaved rounds, the network's streaming per-frame work for the wide view and
the fovea (feature extraction of the new frame, reference context, K thresholds against
the previous frame's cached features) run as two batch-1 passes (what the estimator does:
one cache per view) and as one pass with both views in the batch (the way flip averaging
already batches its mirrored view). Prints the medians and their ratio; nothing is asserted.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
import torch

from bittc_core.estimator import make_estimator
from bittc_core.ttc import tau_to_eta
from controllers.geofence import default_thresholds


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--calls", type=int, default=30)
    ap.add_argument("--thresholds", type=int, default=4)
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    est = make_estimator("bittc", device="cpu")
    net = est.net
    rng = np.random.default_rng(0)
    frames = torch.from_numpy(rng.random((args.calls + 4, 2, 3, 96, 288), dtype=np.float32))  # (call, view, ...)
    thr = np.asarray(default_thresholds(args.thresholds)) * 0.5  # a stride-2 pair at the estimator's 0.1 s
    eta = torch.as_tensor(tau_to_eta(thr, est.dt_s), dtype=torch.float32)

    cache: dict[str, list] = {}

    @torch.inference_mode()
    def two_passes(j: int) -> None:
        feats = cache.setdefault("two", [net.extract(frames[0, v : v + 1]) for v in range(2)])
        for v in range(2):
            latest = net.extract(frames[j + 1, v : v + 1])
            ctx = net.prepare_reference(latest, frames[j + 1, v : v + 1])
            net.classify_eta(ctx, feats[v], eta[None])
            feats[v] = latest

    @torch.inference_mode()
    def one_pass(j: int) -> None:
        feats = cache.setdefault("one", [net.extract(frames[0])])
        latest = net.extract(frames[j + 1])
        ctx = net.prepare_reference(latest, frames[j + 1])
        net.classify_eta(ctx, feats[0], eta[None].expand(2, -1))
        feats[0] = latest

    calls = {"two batch-1 passes": two_passes, "one batch-2 pass": one_pass}
    times = {k: [] for k in calls}
    for j in range(args.calls + 3):
        for name in list(calls)[j % 2 :] + list(calls)[: j % 2]:
            t0 = time.perf_counter()
            calls[name](j)
            if j >= 3:
                times[name].append((time.perf_counter() - t0) * 1e3)
    med = {k: statistics.median(v) for k, v in times.items()}
    print(f"96x288, wide + fovea, K = {args.thresholds}, {args.threads} threads, {args.calls} rounds, streaming")
    for k, v in med.items():
        print(f"  {k:<20} {v:7.2f} ms")
    a, b = med.values()
    print(f"  batched / two passes: {b / a:.2f}")


if __name__ == "__main__":
    main()
