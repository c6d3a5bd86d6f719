"""The shipped weights behave like a TTC estimator, not only like a network of the right shape:
a pair of identical frames (nothing approaches) is outside every geofence, and a pair
zoomed 1.1x about the centre (an approaching wall: eta = 1/1.1, tau = 1 s at 10 Hz) is
inside the 2 s fence and outside the 0.5 s one."""

import cv2
import numpy as np
import pytest

from bittc_core.estimator import make_estimator
from bittc_core.ttc import eta_to_tau

H, W = 96, 288
THRESHOLDS_S = [0.5, 1.0, 2.0, 4.0]


@pytest.fixture(scope="module")
def est():
    return make_estimator("bittc")


def _texture(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return cv2.GaussianBlur(rng.integers(0, 256, (H, W, 3)).astype(np.uint8), (0, 0), 1.5)


def _zoomed(img: np.ndarray, zoom: float) -> np.ndarray:
    m = cv2.getRotationMatrix2D(((W - 1) / 2, (H - 1) / 2), 0.0, zoom)
    return cv2.warpAffine(img, m, (W, H), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)


def _centre(maps: np.ndarray) -> np.ndarray:
    """The central half of each map (away from the reflected borders)."""
    return maps[..., H // 4 : 3 * H // 4, W // 4 : 3 * W // 4]


@pytest.mark.parametrize("seed", [0, 1])
def test_identical_frames_are_outside_every_geofence(est, seed):
    img = _texture(seed)
    est.reset()
    p = est.geofence(img, img, THRESHOLDS_S)
    inside = (_centre(p) > 0.5).mean(axis=(1, 2))
    assert inside.max() < 0.05, dict(zip(THRESHOLDS_S, inside.round(3)))


@pytest.mark.parametrize("seed", [0, 1])
def test_a_wall_at_one_second_is_inside_the_2s_fence_and_outside_the_half_second_one(est, seed):
    prev = _texture(seed)
    assert eta_to_tau(1 / 1.1, est.dt_s) == pytest.approx(1.0)
    est.reset()
    p = est.geofence(prev, _zoomed(prev, 1.1), [0.5, 2.0])
    inside = (_centre(p) > 0.5).mean(axis=(1, 2))
    assert inside[1] > 0.8 and inside[0] < 0.2, inside.round(3)


def test_the_shipped_file_names_its_release_and_the_release_log_marks_it_shipped():
    from pathlib import Path

    from bittc_core.checkpoint import DEFAULT_WEIGHTS, load_checkpoint, release_name

    name = release_name(load_checkpoint(DEFAULT_WEIGHTS))
    assert name is not None
    log = (Path(__file__).resolve().parents[1] / "docs" / "releases.md").read_text()
    assert f"| **{name}** (shipped) |" in log
