"""The committed default weights load without flags and run on a frame pair."""

import numpy as np

from bittc_core.checkpoint import DEFAULT_WEIGHTS, load_checkpoint
from bittc_core.estimator import make_estimator


def test_default_weights_load_and_run():
    assert DEFAULT_WEIGHTS.stat().st_size < 20 * 2**20
    ckpt = load_checkpoint(DEFAULT_WEIGHTS, expected_config="cpu-small-corr")
    assert "train_state" not in ckpt
    est = make_estimator("bittc")
    rng = np.random.default_rng(0)
    a = rng.integers(0, 256, (96, 288, 3), dtype=np.uint8)
    p = est.geofence(a, a, [0.5, 1.0, 2.0])
    assert p.shape == (3, 96, 288) and np.isfinite(p).all() and ((p >= 0) & (p <= 1)).all()
    assert est.continuous(a, a).shape == (96, 288)
