"""The synthetic pairs: exact ground truth consistent with the images."""

import cv2
import numpy as np
import torch

from bittc_core.data.synthetic import SyntheticConfig, SyntheticPairs
from bittc_core.ttc import eta_to_tau


def test_sample_layout_and_determinism():
    ds = SyntheticPairs(3, SyntheticConfig(height_px=48, width_px=96), seed=7)
    s = ds[1]
    assert s["image_prev"].shape == (3, 48, 96) and s["image_prev"].dtype == torch.float32
    assert s["flow_px"].shape == (2, 48, 96) and s["valid"].dtype == torch.bool
    assert s["instance"].dtype == torch.int64 and s["dt_s"].shape == () and s["intrinsics"].shape == (4,)
    assert 0 <= s["image_latest"].min() and s["image_latest"].max() <= 1
    torch.testing.assert_close(s["tau_s"], torch.from_numpy(eta_to_tau(s["eta"].numpy(), 0.1)).float())
    torch.testing.assert_close(ds[1]["image_latest"], s["image_latest"])


def test_flow_warps_previous_onto_latest_and_eta_matches_expansion():
    cfg = SyntheticConfig(noise_std=0.0)
    s = SyntheticPairs(4, cfg, seed=0)[2]
    prev = s["image_prev"].permute(1, 2, 0).numpy()
    latest = s["image_latest"].permute(1, 2, 0).numpy()
    u, v = s["flow_px"].numpy()
    h, w = u.shape
    ys, xs = np.mgrid[0:h, 0:w].astype(np.float32)
    warped = cv2.remap(prev, xs - u, ys - v, cv2.INTER_LINEAR)  # x_prev = x_latest - (u, v)
    err = np.abs(warped - latest).mean(axis=2)
    assert np.median(err) < 0.01 and np.abs(prev - latest).mean() > 3 * np.median(err)
    # a similarity's flow has divergence 2 (1 - eta) per frame: d(x - x_prev)/dx = 1 - 1/s
    inst = s["instance"].numpy()
    eta = s["eta"].numpy()
    du = np.gradient(u, axis=1)
    inner = (inst == 0) & (cv2.erode((inst == 0).astype(np.uint8), np.ones((5, 5))) > 0)
    np.testing.assert_allclose(np.median(du[inner]), 1 - eta[inner][0], atol=1e-4)
