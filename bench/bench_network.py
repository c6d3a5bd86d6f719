"""Latency of the Binary-TTC estimator vs. K thresholds, streaming, 2 threads.

    python bench/bench_network.py [--config cpu-small-corr] [--weights CKPT] [--calls 30] [--size 96x288]

Prints a table; asserts nothing. Same code as ``bittc bench``.
"""

from __future__ import annotations

import sys

from sim.cli.bench_cmd import main

if __name__ == "__main__":
    sys.exit(main())
