"""Latency benchmark of the estimators on the CPU (prints, never asserts); 96x288 unless told.

Streaming protocol: a sequence of distinct random frames f0, f1, ...; call j asks for
(f_j, f_j+1), so the previous frame's features come from the cache and each call pays
for one feature extraction plus the hypotheses. Reported: median wall time [ms] per
call for K thresholds (binary: ``geofence``; continuous: ``continuous``, which stacks
``cont_levels`` maps), and for the binary case the cost of each extra threshold
relative to the one-threshold cost, (t_K - t_1) / ((K - 1) t_1), per K and from the
least-squares slope of t_K over K. Flip averaging (``tta="flip"``: plain and mirrored
frames, see ``bittc_core.estimator.network``) is timed at K = 1 and in continuous mode.

Interleaved rounds: every setting has its own estimator (its own frame cache, the
network shared) and round j times call j of every setting in turn (the order rotated each round), so a slow spell of
the machine (other processes, a virtual machine's stolen time) lands on all settings
alike instead of on whichever setting was being timed then; ratios between settings
are what this protocol keeps steady.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import torch

from bittc_core.estimator import BittcEstimator, FlowEstimator
from bittc_core.model import BinaryTTCNet, count_parameters, get_config

GRAPH_THRESHOLDS = 4  # K of the thresholds graph timed on its own (the geofence controller's default)


@dataclass(frozen=True)
class BenchSettings:
    config: str = "cpu-small-corr"
    height_px: int = 96
    width_px: int = 288
    thresholds: tuple[int, ...] = (1, 2, 4, 8, 16, 24)
    calls: int = 30  # timed calls per setting (after ``warmup``)
    warmup: int = 5
    threads: int = 2
    seed: int = 0

    def __post_init__(self) -> None:
        ks = self.thresholds
        if 1 not in ks or min(ks) < 1 or len(set(ks)) < 2 or len(set(ks)) != len(ks):
            raise ValueError(
                f"BenchSettings.thresholds={ks}: the ratios need K = 1 and at least one more K, all distinct and >= 1"
            )
        if self.calls <= 0 or self.warmup < 1:
            raise ValueError(
                f"BenchSettings: calls={self.calls} must be > 0 and warmup={self.warmup} >= 1 "
                "(the first round extracts both frames, it is not a streaming call)"
            )


def bench_frames(s: BenchSettings, n: int) -> list[np.ndarray]:
    rng = np.random.default_rng(s.seed)
    return [rng.integers(0, 256, (s.height_px, s.width_px, 3), dtype=np.uint8) for _ in range(n)]


def interleaved_median_ms(calls: dict, frames: list[np.ndarray], warmup: int) -> dict:
    """name -> fn(prev, latest); round j times fn(f_j, f_j+1) of every name in turn, the
    order rotated by one each round (so no setting always follows the same other one).
    -> name -> median wall time [ms] over the rounds after ``warmup``."""
    times: dict = {name: [] for name in calls}
    names = list(calls)
    for j in range(len(frames) - 1):
        r = j % len(names)
        for name in names[r:] + names[:r]:
            fn = calls[name]
            t0 = time.perf_counter()
            fn(frames[j], frames[j + 1])
            if j >= warmup:
                times[name].append(time.perf_counter() - t0)
    return {name: float(np.median(t) * 1e3) for name, t in times.items()}


def extra_threshold_ratios(binary_ms: dict) -> tuple[dict, float]:
    """K -> t_K [ms] (K = 1 included) -> ({K: (t_K - t_1) / ((K - 1) t_1)}, slope / t_1)
    with slope the least-squares cost of one more threshold over all K."""
    t1 = binary_ms[1]
    ratios = {k: (t - t1) / ((k - 1) * t1) for k, t in binary_ms.items() if k > 1}
    ks = np.array(list(binary_ms), dtype=float)
    slope = float(np.polyfit(ks, np.array(list(binary_ms.values())), 1)[0])
    return ratios, slope / t1


def _network_estimator(s: BenchSettings, weights: str | None) -> BittcEstimator:
    if weights:
        return BittcEstimator.from_checkpoint(weights, device="cpu")
    torch.manual_seed(s.seed)  # untrained weights time the same as trained ones
    return BittcEstimator(BinaryTTCNet(get_config(s.config)), device=torch.device("cpu"))


def _taus(cfg, k: int) -> np.ndarray:
    return np.geomspace(cfg.tau_min_s, min(cfg.tau_max_s, 5.0), k)


def backend_calls(est, s: BenchSettings, prefix: str = "") -> dict:
    """The timed calls of one backend: K thresholds for each K, and the continuous mode;
    each its own cache (``fork``), the model shared."""
    cfg_tau = (est.tau_range_s[0], est.tau_range_s[1])

    def geofence(k: int):
        e = est.fork()
        thr = np.geomspace(cfg_tau[0], min(cfg_tau[1], 5.0), k)
        return lambda a, b: e.geofence(a, b, thr)

    calls = {f"{prefix}{k}": geofence(k) for k in s.thresholds}
    calls[f"{prefix}continuous"] = est.fork().continuous
    return calls


def run_benchmark(s: BenchSettings = BenchSettings(), weights: str | None = None) -> dict:
    torch.set_num_threads(s.threads)
    est = _network_estimator(s, weights)
    cfg = est.net.config
    frames = bench_frames(s, s.calls + s.warmup + 1)
    print(
        f"config {s.config}: {count_parameters(est.net) / 1e6:.3f} M params, "
        f"{s.height_px}x{s.width_px} px, {torch.get_num_threads()} threads, streaming"
    )

    def geofence(k: int, tta: str = "none"):
        e, thr = est.fork(tta), _taus(cfg, k)
        return lambda a, b: e.geofence(a, b, thr)

    flow, flow_cont = FlowEstimator(), FlowEstimator()
    calls = {k: geofence(k) for k in s.thresholds}
    calls["continuous"] = est.fork().continuous
    calls["flip_1"] = geofence(1, "flip")
    calls["flip_continuous"] = est.fork("flip").continuous
    calls["flow_geofence"] = lambda a, b: flow.geofence(a, b, [1.0, 2.0])
    calls["flow_continuous"] = flow_cont.continuous
    ms = interleaved_median_ms(calls, frames, s.warmup)
    binary = {k: ms[k] for k in s.thresholds}
    ratios, slope_ratio = extra_threshold_ratios(binary)

    print(f"{'K':>4} {'binary ms':>10} {'extra/one':>10}")
    for k, t in binary.items():
        print(f"{k:>4} {t:>10.2f} {ratios.get(k, float('nan')):>10.3f}")
    print(f"extra threshold, least-squares slope over K: {slope_ratio:.3f} of one threshold")
    print(f"continuous ({cfg.cont_levels} maps + AUC + ContRefineNet): {ms['continuous']:.2f} ms")
    print(
        f"flip-averaged (tta flip): one threshold {ms['flip_1']:.2f} ms ({ms['flip_1'] / binary[1]:.2f}x), "
        f"continuous {ms['flip_continuous']:.2f} ms ({ms['flip_continuous'] / ms['continuous']:.2f}x)"
    )
    print(
        f"flow baseline (DIS {flow.config.preset} + affine): geofence {ms['flow_geofence']:.2f} ms, "
        f"continuous {ms['flow_continuous']:.2f} ms"
    )
    return {
        "binary_ms": binary,
        "extra_over_one": ratios,
        "extra_over_one_slope": slope_ratio,
        "continuous_ms": ms["continuous"],
        "flip_one_threshold_ms": ms["flip_1"],
        "flip_continuous_ms": ms["flip_continuous"],
        "flow_geofence_ms": ms["flow_geofence"],
        "flow_continuous_ms": ms["flow_continuous"],
    }


def run_backend_comparison(s: BenchSettings, estimators: dict) -> dict:
    """backend name -> estimator (the same network on each): every K and the continuous mode
    of every backend timed in the same interleaved rounds; prints the table side by side
    with the ratios to the first backend. -> backend -> {binary_ms, continuous_ms, ...}."""
    torch.set_num_threads(s.threads)
    frames = bench_frames(s, s.calls + s.warmup + 1)
    calls = {}
    for name, est in estimators.items():
        calls |= backend_calls(est, s, prefix=f"{name}:")
    ms = interleaved_median_ms(calls, frames, s.warmup)
    names = list(estimators)
    base = names[0]
    out = {}
    for name in names:
        binary = {k: ms[f"{name}:{k}"] for k in s.thresholds}
        ratios, slope = extra_threshold_ratios(binary)
        out[name] = {
            "binary_ms": binary,
            "continuous_ms": ms[f"{name}:continuous"],
            "extra_over_one": ratios,
            "extra_over_one_slope": slope,
        }
    print(
        f"{s.height_px}x{s.width_px} px, {s.threads} threads each, streaming, interleaved rounds "
        f"({s.calls} timed calls per setting)"
    )
    head = (
        f"{'K':>10}" + "".join(f"{n + ' ms':>16}" for n in names) + "".join(f"{n + '/' + base:>24}" for n in names[1:])
    )
    print(head)
    for k in [*s.thresholds, "continuous"]:
        key = "continuous_ms" if k == "continuous" else None
        vals = [out[n][key] if key else out[n]["binary_ms"][k] for n in names]
        print(f"{k!s:>10}" + "".join(f"{v:>16.2f}" for v in vals) + "".join(f"{v / vals[0]:>24.3f}" for v in vals[1:]))
    print(
        f"{'extra/one':>10}"
        + "".join(f"{out[n]['extra_over_one_slope']:>16.3f}" for n in names)
        + "   (least-squares slope over K, in units of one threshold)"
    )
    return out


def time_graphs(s: BenchSettings, estimators: dict, sizes: list[tuple[int, int]]) -> dict:
    """label -> ONNX estimator (``bittc_core.estimator.onnx``; e.g. a float32 and an int8
    export): one run of each graph of each estimator at each size of ``sizes`` timed on its
    own, in the same interleaved rounds; the feeds are the streaming steps' on random frames
    (the first estimator's outputs, the thresholds graph at ``GRAPH_THRESHOLDS`` thresholds).
    Prints the medians side by side with the ratios to the first; -> {(label, size, graph): ms}."""
    from bittc_core.export.graphs import GRAPHS
    from bittc_core.export.quantize import graph_inputs

    rng = np.random.default_rng(s.seed)
    first = next(iter(estimators.values()))
    eta = np.linspace(0.75, 0.95, GRAPH_THRESHOLDS)
    calls, feeds = {}, {}
    for size in sizes:
        frames = [rng.integers(0, 256, (*size, 3), dtype=np.uint8) for _ in range(4)]
        feeds[size] = graph_inputs(first.sessions[size], list(zip(frames[:-1], frames[1:])), eta)
        for label, est in estimators.items():
            for g in GRAPHS:
                calls[(label, size, g)] = est.sessions[size][g]
    times: dict = {key: [] for key in calls}
    keys = list(calls)
    for j in range(s.warmup + s.calls):
        r = j % len(keys)
        for key in keys[r:] + keys[:r]:
            _, size, g = key
            feed = feeds[size][g][j % len(feeds[size][g])]
            t0 = time.perf_counter()
            calls[key].run(None, feed)
            if j >= s.warmup:
                times[key].append(time.perf_counter() - t0)
    ms = {key: float(np.median(t) * 1e3) for key, t in times.items()}
    labels = list(estimators)
    print(
        f"each graph on its own, {s.threads} threads, {s.calls} interleaved rounds "
        f"(thresholds at K = {GRAPH_THRESHOLDS}); ratios to {labels[0]}"
    )
    width = max(14, *(len(label) + 5 for label in labels))
    print(
        f"{'size':<9}{'graph':<12}"
        + "".join(f"{label + ' ms':>{width}}" for label in labels)
        + "".join(f"{label + ' / first':>{width + 4}}" for label in labels[1:])
    )
    for size in sizes:
        for g in GRAPHS:
            vals = [ms[(label, size, g)] for label in labels]
            print(
                f"{f'{size[0]}x{size[1]}':<9}{g:<12}"
                + "".join(f"{v:>{width}.2f}" for v in vals)
                + "".join(f"{v / vals[0]:>{width + 4}.3f}" for v in vals[1:])
            )
    return ms
