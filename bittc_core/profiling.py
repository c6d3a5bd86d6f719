"""Measure a device profile: the streaming latency of the network for K thresholds and in
continuous mode (the interleaved rounds of ``bittc_core.benchmark``), on this machine.
``bittc profile`` fits L = a + b * K to it and writes the profile file (``sim.profile_file``)."""

from __future__ import annotations

import os
import platform
from datetime import date

from bittc_core.benchmark import BenchSettings, backend_calls, bench_frames, interleaved_median_ms


def measure(est, s: BenchSettings) -> dict:
    """-> {"binary": {K: median ms}, "continuous": median ms} of ``est`` (its model shared)."""
    import torch

    torch.set_num_threads(s.threads)
    ms = interleaved_median_ms(backend_calls(est, s), bench_frames(s, s.calls + s.warmup + 1), s.warmup)
    return {"binary": {k: round(ms[str(k)], 3) for k in s.thresholds}, "continuous": round(ms["continuous"], 3)}


def machine() -> dict:
    cpu = platform.processor() or platform.machine()
    try:  # the model name, where Linux tells it
        with open("/proc/cpuinfo") as f:
            cpu = next((line.split(":", 1)[1].strip() for line in f if line.startswith("model name")), cpu)
    except OSError:
        pass
    return {
        "platform": platform.platform(),
        "processor": cpu,
        "cpus": os.cpu_count(),
        "python": platform.python_version(),
        "node": platform.node(),
    }


def versions(backend: str) -> dict:
    from importlib import metadata

    import numpy
    import torch

    out = {"torch": str(torch.__version__), "numpy": str(numpy.__version__)}
    try:
        out = {"bittc-sim": metadata.version("bittc-sim")} | out
    except metadata.PackageNotFoundError:
        pass
    if backend == "onnxruntime":
        import onnxruntime

        out["onnxruntime"] = str(onnxruntime.__version__)
    return out


def today() -> str:
    return date.today().isoformat()
