"""Camera footage in: a clip's frames and capture times, and the frame pairs the network reads.

A clip is a video file (read by OpenCV) or a folder of image frames (sorted by name).
Capture times [s] count from the clip's first frame: from a frame rate, or one timestamp
per frame (``read_timestamps``: seconds, or KITTI's ``YYYY-MM-DD HH:MM:SS.fffffffff``),
strictly increasing.

Pairing (``pair_frames``): the network reads two frames ``pair_dt_s`` apart (its trained
frame interval times a frame stride: 0.1 s x 1 at stride 1). Frame i is paired with the
earlier frame j whose time gap t_i - t_j is nearest to ``pair_dt_s``, when that gap is
within ``PAIR_TOLERANCE`` of it: 30 fps footage pairs frames 3 apart, 10 Hz footage 1
apart. Footage whose frame spacing has no multiple near ``pair_dt_s`` (25 fps: 0.08 or
0.12 s) is refused with the reason, as is a clip none of whose frames can be paired. A
frame without a partner (the first ones; one after a dropped frame) gets no output.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from bittc_core.errors import ConfigError

PAIR_TOLERANCE = 0.1  # [-] largest relative error of a pair's time gap against pair_dt_s
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".ppm")
_KITTI_TIME = re.compile(r"(\d{4}-\d{2}-\d{2} \d{2}:\d{2}:\d{2})(?:\.(\d+))?")


class FootageError(ConfigError):
    """Footage, timestamps or a calibration that cannot be used: names the file or field."""


@dataclass(frozen=True)
class Clip:
    """A clip's source, its frames' capture times [s] from the first (N,), and its frame size."""

    source: str
    times_s: np.ndarray
    size_hw: tuple[int, int]
    frame_paths: tuple[str, ...] | None  # a folder's frames in order; None for a video

    @property
    def kind(self) -> str:
        return "video" if self.frame_paths is None else "frames"

    def frames(self) -> Iterator[np.ndarray]:
        """The frames in order, each uint8 (H, W, 3) RGB; a frame of another size, or a
        video with fewer frames than ``times_s``, raises ``FootageError``."""
        import cv2

        if self.frame_paths is not None:
            for path in self.frame_paths:
                yield _checked(self, cv2.imread(path, cv2.IMREAD_COLOR), path)
            return
        cap = cv2.VideoCapture(self.source)
        try:
            for i in range(len(self.times_s)):
                ok, bgr = cap.read()
                if not ok:
                    raise FootageError(
                        f"{self.source!r}: ends after {i} frames, but {len(self.times_s)} capture times were given"
                    )
                yield _checked(self, bgr, f"{self.source!r} frame {i}")
        finally:
            cap.release()


def _checked(clip: Clip, bgr, what: str) -> np.ndarray:
    import cv2

    if bgr is None:
        raise FootageError(f"{what}: not an image OpenCV can read")
    if bgr.shape[:2] != clip.size_hw:
        raise FootageError(
            f"{what}: {bgr.shape[0]}x{bgr.shape[1]} px, but the clip's first frame is "
            f"{clip.size_hw[0]}x{clip.size_hw[1]} px"
        )
    return cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)


def read_timestamps(path: str | Path) -> np.ndarray:
    """A timestamps file -> (N,) capture times [s] from its first line. A line holds seconds
    (``12.345``) or a KITTI date and time; blank lines are skipped. Times must increase."""
    p = Path(path)
    if not p.is_file():
        raise FootageError(f"timestamps {str(p)!r}: no such file")
    values = []
    for n, line in enumerate(p.read_text().splitlines(), 1):
        text = line.strip()
        if not text:
            continue
        m = _KITTI_TIME.fullmatch(text)
        try:
            if m:
                day = datetime.strptime(m.group(1), "%Y-%m-%d %H:%M:%S").replace(tzinfo=timezone.utc).timestamp()
                values.append(day + (float("0." + m.group(2)) if m.group(2) else 0.0))
            else:
                values.append(float(text))
        except ValueError:
            raise FootageError(
                f"timestamps {str(p)!r} line {n}: {text!r} is neither seconds nor a date and time"
            ) from None
    t = np.asarray(values, dtype=np.float64)
    if len(t) < 2:
        raise FootageError(f"timestamps {str(p)!r}: {len(t)} time(s); a clip needs at least 2 frames")
    back = np.flatnonzero(np.diff(t) <= 0)
    if len(back):
        i = int(back[0]) + 1
        raise FootageError(
            f"timestamps {str(p)!r}: out of order at frame {i} ({t[i] - t[0]:.6f} s after the first, "
            f"not after frame {i - 1}'s {t[i - 1] - t[0]:.6f} s)"
        )
    return t - t[0]


def open_clip(path: str | Path, fps_hz: float | None = None, times_s: np.ndarray | None = None) -> Clip:
    """A video file or a folder of frames -> its ``Clip``. Capture times from ``times_s``
    (one per frame), else ``fps_hz``, else (a video only) the container's frame rate."""
    import cv2

    p = Path(path)
    if fps_hz is not None and not (np.isfinite(fps_hz) and fps_hz > 0):
        raise FootageError(f"fps {fps_hz!r}: must be > 0")
    if p.is_dir():
        paths = tuple(str(f) for f in sorted(p.iterdir()) if f.suffix.lower() in IMAGE_SUFFIXES)
        if not paths:
            raise FootageError(f"clip {str(p)!r}: a folder with no image files ({', '.join(IMAGE_SUFFIXES)})")
        first = cv2.imread(paths[0], cv2.IMREAD_COLOR)
        if first is None:
            raise FootageError(f"clip frame {paths[0]!r}: not an image OpenCV can read")
        count, size, rate = len(paths), first.shape[:2], None
    elif p.is_file():
        cap = cv2.VideoCapture(str(p))
        ok, first = cap.read()
        count = int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
        rate = float(cap.get(cv2.CAP_PROP_FPS) or 0.0)
        cap.release()
        if not ok:
            raise FootageError(f"clip {str(p)!r}: not a video OpenCV can read")
        size, paths = first.shape[:2], None
    else:
        raise FootageError(f"clip {str(p)!r}: no such file or folder")
    if times_s is not None:
        times = np.asarray(times_s, dtype=np.float64)
        if paths is not None and len(times) != count:
            raise FootageError(f"clip {str(p)!r}: {count} frames but {len(times)} capture times")
    else:
        rate = fps_hz or rate
        if not rate:
            raise FootageError(f"clip {str(p)!r}: no frame rate (a folder of frames needs its fps or timestamps)")
        times = np.arange(count, dtype=np.float64) / rate
    if len(times) < 2:
        raise FootageError(f"clip {str(p)!r}: {len(times)} frame(s); pairs need at least 2")
    return Clip(str(p), times, (int(size[0]), int(size[1])), paths)


def pair_frames(times_s: np.ndarray, pair_dt_s: float, tolerance: float = PAIR_TOLERANCE) -> np.ndarray:
    """(N,) capture times [s] -> (N,) the index of each frame's earlier partner, -1 where none
    lies within ``tolerance`` x ``pair_dt_s`` of ``pair_dt_s`` before it (see the module
    docstring). Refuses footage whose typical spacing has no matching multiple, or none of
    whose frames can be paired."""
    t = np.asarray(times_s, dtype=np.float64)
    step = float(np.median(np.diff(t)))
    k = max(int(round(pair_dt_s / step)), 1)
    if abs(k * step - pair_dt_s) > tolerance * pair_dt_s:
        raise FootageError(
            f"frames {step:.4f} s apart ({1 / step:.3g} fps): no frame lies {pair_dt_s:g} s (the network's frame "
            f"interval x stride) before another, the nearest gap is {k * step:.4f} s "
            f"(more than {tolerance:.0%} off); footage at a multiple of {1 / pair_dt_s:g} fps pairs exactly"
        )
    partner = np.full(len(t), -1, dtype=np.int64)
    for i in range(1, len(t)):
        j = int(np.argmin(np.abs(t[i] - t[:i] - pair_dt_s)))
        if abs(t[i] - t[j] - pair_dt_s) <= tolerance * pair_dt_s:
            partner[i] = j
    if (partner < 0).all():
        raise FootageError(
            f"{len(t)} frames over {t[-1]:.3f} s: none lies {pair_dt_s:g} s after another (within {tolerance:.0%})"
        )
    return partner
