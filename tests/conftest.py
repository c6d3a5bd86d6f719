import os

import pytest

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
if os.environ.get("PYTEST_XDIST_WORKER"):
    # pytest -n 2: each worker process takes one core, so torch and onnxruntime get one thread each
    os.environ.setdefault("OMP_NUM_THREADS", "1")


@pytest.fixture(autouse=True)
def _one_torch_thread_per_worker():
    """Under pytest -n 2, a test that sets torch's thread count (``bittc bench`` or
    ``bittc profile`` through ``main``, which set it for their process) leaves it to the
    next: two workers at two threads each on two cores wait on each other's spinning
    threads (a fovea run took 86 s instead of 8)."""
    if not os.environ.get("PYTEST_XDIST_WORKER"):
        yield
        return
    import torch

    threads = torch.get_num_threads()
    yield
    torch.set_num_threads(threads)
