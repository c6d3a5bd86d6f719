"""The synthetic dataset generator: random scenes rendered by the simulator, written in the
dataset format of ``bittc_core.data`` (``generate``; workers in ``pool`` and ``worker``)."""
