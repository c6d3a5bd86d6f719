"""Write a file so that readers see the old file or the whole new one, never a part.

The content goes to a temporary file beside ``path`` (``.<name>.<random>.tmp``), which is
then renamed over ``path``; on an error the temporary file is removed. The temporary
file is created with the permissions of any new file (0o666 less the umask), so the
result is as readable as a plain ``open(path, "w")`` would leave it (``tempfile.mkstemp``
would make it 0o600, unreadable to the other users of a shared data set or run folder).
"""

from __future__ import annotations

import os
import secrets
from pathlib import Path

_NAME_TRIES = 100


def open_temp_beside(path: str | Path) -> tuple[int, Path]:
    """-> (a file descriptor open for writing, its path ``.<name>.<random>.tmp`` beside
    ``path``), a new file with the umask's permissions. The caller renames or removes it."""
    path = Path(path)
    for _ in range(_NAME_TRIES):
        tmp = path.with_name(f".{path.name}.{secrets.token_hex(4)}.tmp")
        try:
            return os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666), tmp
        except FileExistsError:
            continue
    raise FileExistsError(f"no free temporary name beside {str(path)!r} after {_NAME_TRIES} tries")


def write_text_atomic(path: str | Path, text: str) -> None:
    path = Path(path)
    fd, tmp = open_temp_beside(path)
    try:
        with os.fdopen(fd, "w", newline="") as f:
            f.write(text)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
