"""Flag parsing and output-directory checks shared by the subcommands."""

from __future__ import annotations

import os
import re
import tempfile
from pathlib import Path

from bittc_core.errors import CliError


def parse_size(text: str) -> tuple[int, int]:
    """'96x288' -> (96, 288): height x width in px."""
    m = re.fullmatch(r"(\d+)x(\d+)", text.strip().lower())
    if not m:
        raise CliError(f"--size {text!r}: expected HxW in pixels, e.g. 96x288")
    h, w = int(m.group(1)), int(m.group(2))
    if not (16 <= h <= 2048 and 16 <= w <= 4096):
        raise CliError(f"--size {text!r}: height must be in [16, 2048] and width in [16, 4096] px")
    return h, w


def positive_int(name: str, value: int) -> int:
    if value <= 0:
        raise CliError(f"{name} {value}: must be > 0")
    return value


def non_negative_int(name: str, value: int, upper: int | None = None) -> int:
    if value < 0 or (upper is not None and value > upper):
        raise CliError(f"{name} {value}: must be in [0, {upper}]" if upper is not None else f"{name} {value}: must be >= 0")
    return value


MAX_SEED = 2**32 - 1
DEVICES = ("auto", "cpu", "cuda")


def add_device_flag(parser) -> None:
    parser.add_argument("--device", default="auto", help="auto, cpu or cuda")


def check_device(value: str) -> str:
    if value not in DEVICES:
        raise CliError(f"--device {value!r}: expected auto, cpu or cuda")
    return value


def writable_dir(path: str) -> Path:
    """Create ``path`` if needed and prove it writable (nothing is left behind)."""
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise CliError(f"--out {path!r}: exists and is not a directory")
    try:
        p.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(dir=p, prefix=".probe")
        os.close(fd)
        os.unlink(probe)
    except OSError as e:
        raise CliError(f"--out {path!r}: not writable ({e.strerror})") from None
    return p
