"""The driver side of `bittc generate`: samples farmed out to local processes or Ray
tasks, each failure retried up to ``MAX_ATTEMPTS`` times, completions tallied."""

from __future__ import annotations

import sys
import time
from dataclasses import asdict, dataclass, field

from bittc_core.data.format import sample_dirname
from sim.datagen.config import LOCAL_CHUNK, MAX_ATTEMPTS, RAY_CHUNK, STEADY_MIN_S, STEADY_MIN_SAMPLES
from sim.datagen.worker import close_worker, make_many, make_sample, worker_init


def _progress(total: int, enabled: bool):
    from tqdm import tqdm

    return tqdm(total=total, unit="sample", disable=not enabled, smoothing=0.1, file=sys.stderr)


@dataclass
class _Tally:
    """The driver's record of worker results: successes (with their completion times),
    retries to queue, final failures."""

    todo: list[int]
    bar: object
    split: str
    written: int = 0
    failed: list = field(default_factory=list)
    done_at_s: list = field(default_factory=list)  # perf_counter() of each success

    def __post_init__(self) -> None:
        self.attempts = {i: 0 for i in self.todo}

    def account(self, results) -> list[int]:
        """Tally results; returns the indices to try again."""
        retry = []
        for index, _sec, err in results:
            self.attempts[index] += 1
            if err is None:
                self.written += 1
                self.done_at_s.append(time.perf_counter())
                self.bar.update(1)
            elif self.attempts[index] < MAX_ATTEMPTS:
                print(
                    f"sample {self.split}/{index} failed (try {self.attempts[index]}), retrying:\n{err}",
                    file=sys.stderr,
                )
                retry.append(index)
            else:
                print(f"sample {self.split}/{index} failed {MAX_ATTEMPTS} times:\n{err}", file=sys.stderr)
                self.failed.append(index)
        return retry


def steady_rate(
    done_at_s: list[float], skip: int, min_samples: int = STEADY_MIN_SAMPLES, min_s: float = STEADY_MIN_S
) -> float | None:
    """Samples/s between the ``skip``-th and the last completion: the throughput once
    the workers are up (process start, imports and the first world are left out).

    None unless that window holds at least ``min_samples`` completions after the
    ``skip``-th and spans at least ``min_s`` seconds: results arrive a chunk at a time,
    so a shorter window measures the burst, not the rate."""
    if len(done_at_s) < skip + 1 + max(min_samples, 1):
        return None
    span_s = done_at_s[-1] - done_at_s[skip]
    if span_s <= 0.0 or span_s < min_s:
        return None
    return (len(done_at_s) - 1 - skip) / span_s


def run_local(cfg, split_dir, split, todo, workers, _addr, progress):
    cfg_dict = asdict(cfg)
    queue = list(todo)
    bar = _progress(len(todo), progress)
    tally = _Tally(todo, bar, split)
    pool = None
    if workers > 1:
        import multiprocessing as mp

        pool = mp.get_context("spawn").Pool(
            workers, initializer=worker_init, initargs=(cfg_dict,), maxtasksperchild=2000
        )
    try:
        while queue:
            args = [(cfg_dict, str(split_dir), split, i) for i in queue]
            results = pool.imap_unordered(_star, args, chunksize=LOCAL_CHUNK) if pool else map(_star, args)
            queue = tally.account(results)
    finally:
        bar.close()
        if pool is not None:
            pool.close()
            pool.join()
        close_worker()
    return tally


def _star(args):
    return make_sample(*args)


def run_ray(cfg, split_dir, split, todo, workers, address, progress):
    import ray

    from bittc_core.ray_start import start_ray

    started_here = start_ray(workers, address)
    remote = ray.remote(num_cpus=1, max_retries=MAX_ATTEMPTS - 1, retry_exceptions=True)(make_many)
    cfg_dict = asdict(cfg)
    bar = _progress(len(todo), progress)
    tally = _Tally(todo, bar, split)
    try:
        queue = list(todo)
        while queue:
            refs = [
                remote.remote(cfg_dict, str(split_dir), split, queue[k : k + RAY_CHUNK])
                for k in range(0, len(queue), RAY_CHUNK)
            ]
            queue = []
            while refs:
                done, refs = ray.wait(refs, num_returns=1)
                try:
                    results = ray.get(done[0])
                except Exception as e:  # the task itself died MAX_ATTEMPTS times
                    print(f"a Ray task failed after its retries: {e}", file=sys.stderr)
                    continue
                queue += tally.account(results)
        # samples of tasks that died without a result: still missing on disk
        missing = [i for i in todo if not (split_dir / sample_dirname(i)).exists() and i not in tally.failed]
        tally.failed.extend(missing)
    finally:
        bar.close()
        if started_here:
            ray.shutdown()
    return tally
