"""Silence the C-level prints of PyBullet (its build banner and 'argv[0]=' on connect)."""

from __future__ import annotations

import contextlib
import os
import sys


@contextlib.contextmanager
def c_output_suppressed():
    """Redirect file descriptors 1 and 2 to /dev/null for the duration (C code included)."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, 1)
        os.dup2(devnull, 2)
        yield
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for fd in (*saved, devnull):
            os.close(fd)
