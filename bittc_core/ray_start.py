"""Ray for the drivers that farm work out (`bittc generate`, `bittc sweep`)."""

from __future__ import annotations


def start_ray(workers: int, address: str | None) -> bool:
    """Connect to the cluster at ``address``, or start a local instance with ``workers``
    CPUs, unless Ray is up already; returns whether it was started here (then the caller
    shuts it down)."""
    import ray

    if ray.is_initialized():
        return False
    if address:
        ray.init(address=address, log_to_driver=False)
    else:
        ray.init(num_cpus=workers, include_dashboard=False, log_to_driver=False)
    return True
