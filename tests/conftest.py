import os

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
if os.environ.get("PYTEST_XDIST_WORKER"):
    # pytest -n 2: each worker process takes one core, so torch and onnxruntime get one thread each
    os.environ.setdefault("OMP_NUM_THREADS", "1")
