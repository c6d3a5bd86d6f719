"""A deterministic, fast writer of compressed ``.npz`` files (``np.load`` reads them).

An ``.npz`` is a ZIP archive of ``.npy`` members. This writes the archive itself, with
members deflated by ISA-L (``isal``, level 1): about ten times faster than zlib's
fastest level on float maps for a 3 % larger file, and still plain deflate, so numpy,
``zipfile`` and any unzip tool read it. Timestamps are fixed and nothing else varies, so
the bytes depend on the arrays (and the ``isal`` version) only.
"""

from __future__ import annotations

import io
import struct
import zlib
from pathlib import Path

import numpy as np
from isal import isal_zlib

DEFLATE_LEVEL = 1  # ISA-L levels are 0-3; 1 and 2 give the same size on our maps
_METHOD_DEFLATE = 8
_VERSION = 20  # ZIP 2.0: deflate
_MADE_BY = (3 << 8) | _VERSION  # Unix, so that the permission bits below are read
_DOS_DATE = (1 << 5) | 1  # 1980-01-01
_DOS_TIME = 0
_MODE = 0o100644 << 16  # regular file, rw-r--r--
_LOCAL = struct.Struct("<IHHHHHIIIHH")
_CENTRAL = struct.Struct("<IHHHHHHIIIHHHHHII")
_END = struct.Struct("<IHHHHIIH")


def npy_bytes(arr: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.lib.format.write_array(buf, np.ascontiguousarray(arr), allow_pickle=False)
    return buf.getvalue()


def save_npz(path: str | Path, arrays: dict[str, np.ndarray]) -> None:
    """Write ``arrays`` as a compressed .npz at ``path`` (members in dict order)."""
    out = bytearray()
    central = bytearray()
    for name, arr in arrays.items():
        raw = npy_bytes(arr)
        if len(raw) >= 0xFFFFFFFF:
            raise ValueError(f"array {name!r}: {len(raw)} bytes needs ZIP64, not supported")
        packed = isal_zlib.compress(raw, DEFLATE_LEVEL, wbits=-15)  # raw deflate stream
        fname = f"{name}.npy".encode()
        crc = zlib.crc32(raw)
        offset = len(out)
        out += _LOCAL.pack(
            0x04034B50, _VERSION, 0, _METHOD_DEFLATE, _DOS_TIME, _DOS_DATE, crc, len(packed), len(raw), len(fname), 0
        )
        out += fname + packed
        central += _CENTRAL.pack(
            0x02014B50,
            _MADE_BY,
            _VERSION,
            0,
            _METHOD_DEFLATE,
            _DOS_TIME,
            _DOS_DATE,
            crc,
            len(packed),
            len(raw),
            len(fname),
            0,
            0,
            0,
            0,
            _MODE,
            offset,
        )
        central += fname
    n = len(arrays)
    end = _END.pack(0x06054B50, 0, 0, n, n, len(central), len(out), 0)
    Path(path).write_bytes(bytes(out + central + end))
