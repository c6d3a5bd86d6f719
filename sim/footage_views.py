"""A clip's views in the network's pixels: crops, a region of interest, fence shares, pictures.

A view is a crop box (u0, v0, u1, v1) [native px, u1 and v1 exclusive] of the native
frame resized to (H, W) [px] (area interpolation); the wide view's box is the whole frame.
"""

from __future__ import annotations

import cv2
import numpy as np

DECISION_PROB = 0.5  # a pixel is inside a fence where p > DECISION_PROB


def crop_view(frame: np.ndarray, box, size_hw) -> np.ndarray:
    """uint8 (H_native, W_native, 3) -> the view: the box's pixels resized to ``size_hw``."""
    u0, v0, u1, v1 = box
    return cv2.resize(frame[v0:v1, u0:u1], size_hw[::-1], interpolation=cv2.INTER_AREA)


def roi_in_view(roi, box, size_hw):
    """A region (u0, v0, u1, v1) [native px] -> ((u0, v0), (u1, v1)) in the view's pixels
    (every view pixel it touches), or None where it misses the view (or is None)."""
    if roi is None:
        return None
    u0, v0, u1, v1 = box
    sx, sy = size_hw[1] / (u1 - u0), size_hw[0] / (v1 - v0)
    a = (max(int(np.floor((roi[0] - u0) * sx)), 0), max(int(np.floor((roi[1] - v0) * sy)), 0))
    b = (min(int(np.ceil((roi[2] - u0) * sx)), size_hw[1]), min(int(np.ceil((roi[3] - v0) * sy)), size_hw[0]))
    return (a, b) if b[0] > a[0] and b[1] > a[1] else None


def inside_shares(maps: np.ndarray, roi) -> tuple[list[float], list[float | None]]:
    """(K, H, W) fence maps -> (share of the view's pixels inside each fence, the same over
    ``roi`` from ``roi_in_view``, None each without one)."""
    whole = [float((m > DECISION_PROB).mean()) for m in maps]
    if roi is None:
        return whole, [None] * len(maps)
    (u0, v0), (u1, v1) = roi
    return whole, [float((m[v0:v1, u0:u1] > DECISION_PROB).mean()) for m in maps]


def side_by_side(images: list[np.ndarray], scale: int) -> np.ndarray:
    """Views left to right, each scaled by ``scale`` (nearest), later ones to the first's height."""
    tiles = [
        cv2.resize(im, (im.shape[1] * scale, im.shape[0] * scale), interpolation=cv2.INTER_NEAREST) for im in images
    ]
    h = tiles[0].shape[0]
    tiles = [t if t.shape[0] == h else cv2.resize(t, (round(t.shape[1] * h / t.shape[0]), h)) for t in tiles]
    return np.concatenate(tiles, axis=1)


def fence_columns(row: dict, view: str, thresholds, maps, roi, with_roi: bool) -> None:
    """``row`` gains the share of ``view``'s pixels inside each fence of ``maps`` (K, H, W),
    ``<view>_inside_<tau>s``, and with ``with_roi`` over ``roi`` (``<view>_roi_inside_<tau>s``,
    empty where the region misses the view)."""
    whole, inside_roi = inside_shares(maps, roi)
    for t, a, b in zip(thresholds, whole, inside_roi):
        row[f"{view}_inside_{t:g}s"] = round(a, 6)
        if with_roi:
            row[f"{view}_roi_inside_{t:g}s"] = "" if b is None else round(b, 6)
