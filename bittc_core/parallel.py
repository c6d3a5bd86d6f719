"""How many worker processes a job starts, and an OS lock on an output folder.

Workers: a pool never gets more workers than tasks, a count above the machine's cores
is allowed with a warning (each worker then gets one thread: threads x workers stays
within the cores), and a count above ``max_workers()`` is refused as a typo. Locks: a
folder that a running ``sweep`` writes into holds a lock file ``.bittc.lock`` locked with
``fcntl.flock``; ``generate`` locks ``.NAME.lock`` beside its dataset folder NAME (the
dataset holds only the dataset) and ``train`` ``.NAME.lock`` beside its checkpoint
NAME.pt. A second run into a locked output is refused with the holder's process id. The
OS drops the lock when its process dies, so an output left by a killed run is never
blocked (``--resume`` works after a SIGKILL).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

from bittc_core.errors import ConfigError

LOCK_FILE = ".bittc.lock"


def cpu_count() -> int:
    return os.cpu_count() or 1


def max_workers() -> int:
    """More worker processes than this is surely a typo: 4 per core, at least 16."""
    return max(16, 4 * cpu_count())


def check_workers(requested, what: str = "workers", local: bool = True) -> int:
    """A worker count in [1, ``max_workers()``] (``local=False``, workers on a Ray cluster:
    only >= 1, the cluster's size is not this machine's); anything else refused by value."""
    if isinstance(requested, bool) or not isinstance(requested, int) or requested < 1:
        raise ConfigError(f"{what} {requested!r}: must be an integer >= 1")
    if local and requested > max_workers():
        raise ConfigError(
            f"{what} {requested}: more than {max_workers()} worker processes on a {cpu_count()}-core machine "
            "is refused (each is a full process with its own renderer and network)"
        )
    return requested


def bounded_workers(requested, tasks: int, what: str = "workers", local: bool = True) -> int:
    """-> the worker count to start for ``tasks`` tasks: at most ``tasks``; refused as
    ``check_workers`` refuses; warned on stderr above the machine's cores (local workers)."""
    check_workers(requested, what, local)
    if local and requested > cpu_count():
        print(
            f"warning: {what} {requested} on {cpu_count()} cores: the workers share the cores "
            "(one thread each), so each runs slower and measured latency grows",
            file=sys.stderr,
        )
    n = max(1, min(requested, tasks))
    if n < requested:
        print(f"note: {requested} {what} for {tasks} task(s): starting {n}", file=sys.stderr)
    return n


def threads_per_worker(workers: int) -> int:
    """Torch threads per worker so that threads x workers stays within the cores."""
    return max(1, cpu_count() // max(workers, 1))


class OutputLock:
    """An exclusive OS lock on ``folder`` for as long as the ``with`` block runs.

    Raises ConfigError naming the holder's process id when another live process holds it."""

    def __init__(self, folder: str | Path, what: str = "output folder", name: str = LOCK_FILE) -> None:
        self.path = Path(folder) / name
        self.what = what
        self.target = Path(folder)  # what the messages name
        self._fd: int | None = None

    @classmethod
    def beside(cls, target: str | Path, what: str = "output folder") -> OutputLock:
        """A lock on ``target`` held in ``.NAME.lock`` next to it, so that ``target`` holds only
        what the run writes. Placed beside the resolved path: two spellings of one folder
        (relative, through a symlink) take the same lock."""
        real = Path(target).resolve()
        lock = cls(real.parent, what, name=f".{real.name}.lock")
        lock.target = Path(target)
        return lock

    def __enter__(self) -> OutputLock:
        return self if self._fd is not None else self.acquire()

    def __exit__(self, exc_type, *exc) -> None:
        # a run refused or failed inside the lock leaves nothing it created behind
        self.release(discard=exc_type is not None)

    def acquire(self) -> OutputLock:
        """Take the lock (ConfigError when a live process holds it or the folder cannot be written)."""
        import fcntl

        self._new_dir = not self.path.parent.exists()
        self._new_file = not self.path.exists()
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as e:
            raise ConfigError(f"{self.what} {str(self.target)!r}: cannot write there ({e.strerror})") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 32, 0).decode(errors="replace").strip() or "unknown"
            os.close(fd)
            raise ConfigError(
                f"{self.what} {str(self.target)!r} is in use by a running process (pid {holder}); "
                "wait for it, or choose another folder"
            ) from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        self._fd = fd
        return self

    def release(self, discard: bool = False) -> None:
        """Unlock; with ``discard``, also remove the lock file and the folder if this lock created them
        (the folder only when nothing else is in it)."""
        if self._fd is None:
            return
        import fcntl

        if discard and self._new_file:
            self.path.unlink(missing_ok=True)
            if self._new_dir:
                try:
                    self.path.parent.rmdir()
                except OSError:
                    pass
        fcntl.flock(self._fd, fcntl.LOCK_UN)
        os.close(self._fd)
        self._fd = None
