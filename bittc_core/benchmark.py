"""Latency benchmark of the estimators at 96x288 on the CPU (prints, never asserts).

Streaming protocol: a sequence of distinct random frames f0, f1, ...; call j asks for
(f_j, f_j+1), so the previous frame's features come from the cache and each call pays
for one feature extraction plus the hypotheses. Reported: median wall time [ms] per
call for K thresholds (binary: ``geofence``; continuous: ``continuous``, which stacks
``cont_levels`` maps), and for the binary case the cost of each extra threshold
relative to the one-threshold cost, (t_K - t_1) / ((K - 1) t_1).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import torch

from bittc_core.estimator import BittcEstimator, FlowEstimator
from bittc_core.model import BinaryTTCNet, count_parameters, get_config


@dataclass(frozen=True)
class BenchSettings:
    config: str = "cpu-small"
    height_px: int = 96
    width_px: int = 288
    thresholds: tuple[int, ...] = (1, 2, 4, 8, 16, 24)
    calls: int = 30  # timed calls per setting (after ``warmup``)
    warmup: int = 5
    threads: int = 2
    seed: int = 0


def _frames(s: BenchSettings, n: int) -> list[np.ndarray]:
    rng = np.random.default_rng(s.seed)
    return [rng.integers(0, 256, (s.height_px, s.width_px, 3), dtype=np.uint8) for _ in range(n)]


def _median_ms(fn, frames: list[np.ndarray], warmup: int) -> float:
    times = []
    for j in range(len(frames) - 1):
        t0 = time.perf_counter()
        fn(frames[j], frames[j + 1])
        if j >= warmup:
            times.append(time.perf_counter() - t0)
    return float(np.median(times) * 1e3)


def run_benchmark(s: BenchSettings = BenchSettings(), weights: str | None = None) -> dict:
    torch.set_num_threads(s.threads)
    if weights:
        est = BittcEstimator.from_checkpoint(weights, device="cpu")
    else:  # untrained weights time the same as trained ones
        torch.manual_seed(s.seed)
        est = BittcEstimator(BinaryTTCNet(get_config(s.config)), device=torch.device("cpu"))
    cfg = est.net.config
    frames = _frames(s, s.calls + s.warmup + 1)
    taus = lambda k: np.geomspace(cfg.tau_min_s, min(cfg.tau_max_s, 5.0), k)  # noqa: E731
    print(f"config {s.config}: {count_parameters(est.net) / 1e6:.3f} M params, "
          f"{s.height_px}x{s.width_px} px, {torch.get_num_threads()} threads, streaming")
    binary = {}
    for k in s.thresholds:
        thr = taus(k)
        est.reset()
        binary[k] = _median_ms(lambda a, b: est.geofence(a, b, thr), frames, s.warmup)
    est.reset()
    continuous = _median_ms(est.continuous, frames, s.warmup)
    flow = FlowEstimator()
    flow_bin = _median_ms(lambda a, b: flow.geofence(a, b, [1.0, 2.0]), frames, s.warmup)
    flow_cont = _median_ms(flow.continuous, frames, s.warmup)

    t1 = binary[s.thresholds[0]]
    print(f"{'K':>4} {'binary ms':>10} {'extra/one':>10}")
    for k, t in binary.items():
        extra = (t - t1) / ((k - 1) * t1) if k > 1 else float("nan")
        print(f"{k:>4} {t:>10.2f} {extra:>10.3f}")
    print(f"continuous ({cfg.cont_levels} maps + AUC + ContRefineNet): {continuous:.2f} ms")
    print(f"flow baseline (DIS {flow.config.preset} + affine): geofence {flow_bin:.2f} ms, "
          f"continuous {flow_cont:.2f} ms")
    return {"binary_ms": binary, "continuous_ms": continuous,
            "flow_geofence_ms": flow_bin, "flow_continuous_ms": flow_cont}
