"""Write a text file so that readers see the old file or the whole new one, never a part.

The text goes to a temporary file beside ``path`` (``.<name>.<random>.tmp``), which is
then renamed over ``path``; on an error the temporary file is removed.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path


def write_text_atomic(path: str | Path, text: str) -> None:
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", newline="") as f:
            f.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
