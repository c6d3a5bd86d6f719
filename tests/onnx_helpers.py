"""A tiny network's checkpoint and synthetic approach pairs for the ONNX tests."""

from __future__ import annotations

import dataclasses

import numpy as np
import torch

from bittc_core.checkpoint import make_payload, save_checkpoint
from bittc_core.model import BinaryTTCNet, get_config

SIZE = (24, 48)  # (H, W) of the tiny network's test frames
HALF = (24, 24)  # (H, W) of a view half as wide (as the fovea beside the wide view)


def tiny_checkpoint(path, seed: int = 0, shift_px: int = 0, column: bool = False, column_input: bool = False):
    torch.manual_seed(seed)
    # the correlation volume too (its shifted correlations with ``shift_px``, its column
    # correlations with ``column``, and the source warped by columns as SegNet's second
    # input with ``column_input``)
    cfg = dataclasses.replace(
        get_config("tiny"), corr_groups=4, corr_shift_px=shift_px, corr_column=column, column_input=column_input
    )
    net = BinaryTTCNet(cfg).eval()
    for part in ("shift",) * bool(shift_px) + ("column",) * column + ("column_src",) * column_input:
        with torch.no_grad():  # the added parts' convs start at zero: make them count
            getattr(net.segnet, f"{part}_first").weight.normal_(0.0, 0.3)
            getattr(net.segnet, f"{part}_last").weight.normal_(0.0, 0.3)
    save_checkpoint(path, make_payload(net, "tiny", {"frame_dt_s": cfg.frame_dt_s}))
    return path


def zoom_pair(h: int, w: int, seed: int, zoom: float = 1.05):
    """A smooth random texture and the same texture zoomed about the centre (approaching)."""
    import cv2

    rng = np.random.default_rng(seed)
    base = cv2.resize(rng.integers(0, 256, (h // 4 + 1, w // 4 + 1, 3), dtype=np.uint8), (w, h))
    m = cv2.getRotationMatrix2D(((w - 1) / 2, (h - 1) / 2), 0.0, zoom)
    return base, cv2.warpAffine(base, m, (w, h), borderMode=cv2.BORDER_REFLECT)
