"""Data-generation throughput, measured in one run: 1 worker, 2 workers, Ray vs local.

Usage: python bench/bench_generate.py [--samples N] [--size HxW] [--ground-texture detailed|smooth]
Prints samples/s per worker at the given size (target >= 20 per core at 96x288), the
2-worker / 1-worker ratio (target >= 1.7 on 2 cores) and Ray / local with the same
worker count (target: Ray within 15 %). Each figure is the steady-state rate of one
run of N samples (``steady_samples_per_s`` of the run statistics: completions after
the first chunk per worker, up to the last one), so start-up (process spawn, imports,
texture bank, the first world) is left out; the local Ray instance is started and
its workers warmed once before the Ray run. Nothing is asserted.
"""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

from sim.datagen.generate import GenerationConfig, generate  # noqa: E402


def timed(cfg: GenerationConfig, n: int, workers: int, backend: str) -> float:
    """Steady-state samples/s of one fresh run of ``n`` samples."""
    with tempfile.TemporaryDirectory() as d:
        run = generate(Path(d), cfg, "train", n, workers, backend, progress=False)
    if run["steady_samples_per_s"] is None:
        raise SystemExit(f"--samples {n}: too few to measure a steady rate with {workers} worker(s)")
    return run["steady_samples_per_s"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=200)
    ap.add_argument("--size", default="96x288")
    ap.add_argument("--no-ray", action="store_true")
    ap.add_argument("--ground-texture", default="detailed", help="detailed (default) or smooth")
    args = ap.parse_args()
    h, w = (int(v) for v in args.size.split("x"))
    cfg = GenerationConfig(seed=123, height_px=h, width_px=w, ground_texture=args.ground_texture)
    print(
        f"{os.cpu_count()} cores, {h}x{w}, {args.ground_texture} ground, steady state of runs of {args.samples} samples"
    )
    one = timed(cfg, args.samples, 1, "local")
    print(f"local, 1 worker : {one:6.2f} samples/s  ({one:.2f} per worker; target >= 20 per core)")
    two = timed(cfg, args.samples, 2, "local")
    print(f"local, 2 workers: {two:6.2f} samples/s  ({two / 2:.2f} per worker)")
    print(f"2-worker / 1-worker ratio: {two / one:.2f}  (target >= 1.7)")
    if not args.no_ray:
        try:
            import ray  # noqa: F401
        except ImportError:
            print("ray: not installed (pip install 'bittc-sim[ray]'); skipped")
            return
        import ray

        ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
        with tempfile.TemporaryDirectory() as d:  # start Ray's worker processes before timing
            generate(Path(d), cfg, "train", 8, 2, "ray", progress=False)
        r = timed(cfg, args.samples, 2, "ray")
        ray.shutdown()
        print(f"ray, 2 workers  : {r:6.2f} samples/s; ray / local = {r / two:.2f}  (target >= 0.85)")


if __name__ == "__main__":
    main()
