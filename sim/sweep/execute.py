"""One sweep run into its folder, and the backends that execute many.

A run writes into ``DIR/runs/.<run_id>.partial`` and the folder is renamed to
``DIR/runs/<run_id>`` once every file is written: a run's folder is whole or absent,
so ``--resume`` can trust every folder it finds. A run that raises is tried once more
(on either backend) and then recorded with its error; the sweep goes on.

Threads: each worker process pins torch to ``threads_per_worker`` threads (the CPU's
cores divided among the workers) and numpy's BLAS and OpenCV to one, so that measured
latencies are stable; with several workers on a small machine each estimator gets fewer
cores, and measured latency grows accordingly (the report says so).
"""

from __future__ import annotations

import os
import shutil
import sys
import traceback
from dataclasses import dataclass
from pathlib import Path

from bittc_core.parallel import threads_per_worker
from sim.sweep.plan import RunSpec, SweepSettings

MAX_TRIES = 2  # a failed run is tried once more, then reported

_CONTROLLERS: dict = {}  # per process: (name, K, weights, stride) -> controller, built once
_CASES: dict = {}  # per process: suites -> {case name: case}


@dataclass
class RunResult:
    spec: RunSpec
    summary: dict | None  # None when the run failed
    error: str | None = None
    tries: int = 1


def pin_threads(threads: int) -> None:
    """torch to ``threads`` threads, BLAS and OpenCV to one (before the first use)."""
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    os.environ.setdefault("OMP_NUM_THREADS", str(threads))
    import torch

    torch.set_num_threads(threads)


def _controller(spec: RunSpec, settings: SweepSettings):
    import controllers
    from controllers.geofence import default_thresholds

    key = (
        spec.controller,
        spec.num_alphas,
        settings.weights,
        settings.frame_stride,
        settings.net_backend,
        settings.onnx,
    )
    if key not in _CONTROLLERS:
        kw = {}
        if spec.controller in controllers.ESTIMATOR_CONTROLLERS:
            kw["thresholds_s"] = default_thresholds(spec.num_alphas)
            if settings.frame_stride is not None:
                kw["frame_stride"] = settings.frame_stride
        if spec.controller == "geofence" and settings.weights is not None:
            kw["weights"] = settings.weights
        if spec.controller == "geofence" and settings.net_backend != "torch":
            kw["backend"], kw["onnx"] = settings.net_backend, settings.onnx
        _CONTROLLERS[key] = controllers.make(spec.controller, **kw)
    return _CONTROLLERS[key]


def _case(settings: SweepSettings, name: str):
    if settings.suites not in _CASES:
        from sim.sweep.plan import suite_cases

        _CASES[settings.suites] = {c.name: c for c in suite_cases(settings.suites)}
    return _CASES[settings.suites][name]


def run_dir(out: Path, spec: RunSpec) -> Path:
    return out / "runs" / spec.run_id


def execute_run(spec: RunSpec, settings: SweepSettings, out: str) -> tuple[dict | None, str | None]:
    """Run ``spec`` into its folder; -> (summary, None) or (None, the error's traceback)."""
    from sim.camera import CameraConfig
    from sim.latency import parse_latency
    from sim.runner import run_case

    final = run_dir(Path(out), spec)
    partial = final.with_name(f".{final.name}.partial")
    try:
        case = _case(settings, spec.case)
        shutil.rmtree(partial, ignore_errors=True)
        summary = run_case(
            case,
            _controller(spec, settings),
            CameraConfig(fovea_zoom=spec.fovea_zoom),
            spec.seed,
            partial,
            video=spec.case in settings.video_cases,
            latency=parse_latency(spec.latency),
        )
        shutil.rmtree(final, ignore_errors=True)
        os.replace(partial, final)
        return summary, None
    except Exception:
        shutil.rmtree(partial, ignore_errors=True)
        return None, traceback.format_exc(limit=8)


def _worker_init(threads: int) -> None:
    pin_threads(threads)


def _star(args):
    return args[0].index, execute_run(*args)


def run_local(todo: list[RunSpec], settings: SweepSettings, out: Path, workers: int, on_result) -> None:
    """Execute ``todo`` on ``workers`` processes (1: in this process); ``on_result(RunResult)``
    is called as each run ends (after its retry)."""
    by_index = {s.index: s for s in todo}
    tries = {s.index: 0 for s in todo}
    queue = list(todo)
    pool, caller_threads = None, None
    if workers > 1:
        import multiprocessing as mp

        pool = mp.get_context("spawn").Pool(workers, initializer=_worker_init, initargs=(threads_per_worker(workers),))
    else:  # this process runs them: its caller gets its thread count back
        import torch

        caller_threads = torch.get_num_threads()
        pin_threads(threads_per_worker(1))
    try:
        while queue:
            args = [(s, settings, str(out)) for s in queue]
            results = pool.imap_unordered(_star, args) if pool else map(_star, args)
            queue = []
            for index, (summary, error) in results:
                tries[index] += 1
                spec = by_index[index]
                if error is not None and tries[index] < MAX_TRIES:
                    print(f"run {spec.run_id} failed (try {tries[index]}), retrying:\n{error}", file=sys.stderr)
                    queue.append(spec)
                    continue
                on_result(RunResult(spec, summary, error, tries[index]))
    finally:
        if pool is not None:
            pool.close()
            pool.join()
        if caller_threads is not None:
            torch.set_num_threads(caller_threads)


def run_ray(
    todo: list[RunSpec], settings: SweepSettings, out: Path, workers: int, address: str | None, on_result
) -> None:
    """The same on Ray: a local instance with ``workers`` CPUs, or the cluster at
    ``address`` (whose workers must see ``out`` and have this package installed). A task
    whose worker dies is retried by Ray once; a run that raises is retried once by the
    driver; either way a run that still fails is reported, never dropped."""
    import ray

    from bittc_core.ray_start import start_ray

    started_here = start_ray(workers, address)
    remote = ray.remote(num_cpus=1, max_retries=MAX_TRIES - 1)(_ray_task)
    threads = threads_per_worker(workers)
    tries = {s.index: 0 for s in todo}
    try:
        pending = {remote.remote(s, settings, str(out), threads): s for s in todo}
        while pending:
            done, _ = ray.wait(list(pending), num_returns=1)
            spec = pending.pop(done[0])
            tries[spec.index] += 1
            try:
                summary, error = ray.get(done[0])
            except Exception as e:  # the worker died on every try
                summary, error = None, f"Ray task failed: {type(e).__name__}: {e}"
                tries[spec.index] = MAX_TRIES
            if error is not None and tries[spec.index] < MAX_TRIES:
                print(f"run {spec.run_id} failed (try {tries[spec.index]}), retrying:\n{error}", file=sys.stderr)
                pending[remote.remote(spec, settings, str(out), threads)] = spec
                continue
            on_result(RunResult(spec, summary, error, tries[spec.index]))
    finally:
        if started_here:
            ray.shutdown()


def _ray_task(spec: RunSpec, settings: SweepSettings, out: str, threads: int):
    pin_threads(threads)
    return execute_run(spec, settings, out)
