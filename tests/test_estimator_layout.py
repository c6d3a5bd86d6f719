"""The torch estimator runs the network channels-last on a CPU: the same fences as the
network in its default layout, at the wide view's size and at the fovea's."""

import copy

import numpy as np
import pytest
import torch

from bittc_core.estimator import BittcEstimator
from bittc_core.model import BinaryTTCNet, get_config
from bittc_core.ttc import tau_to_eta

THRESHOLDS_S = [0.8, 1.21, 1.84, 2.8]


@pytest.fixture(scope="module")
def net():
    torch.manual_seed(0)
    net = BinaryTTCNet(get_config("cpu-small-corr")).eval()
    for layer in (net.segnet.corr_first, net.segnet.corr_last):  # zero at init: give them weight
        layer.weight.data.normal_(0.0, 0.1)
    return net


@pytest.mark.parametrize("size_hw", [(96, 288), (96, 144), (48, 99)])
def test_channels_last_estimator_gives_the_networks_fences(net, size_hw):
    est = BittcEstimator(copy.deepcopy(net), device=torch.device("cpu"))
    rng = np.random.default_rng(1)
    prev, latest = (rng.integers(0, 256, (*size_hw, 3), dtype=np.uint8) for _ in range(2))
    got = est.geofence(prev, latest, THRESHOLDS_S)
    to_t = lambda a: torch.from_numpy(a).permute(2, 0, 1)[None].float() / 255.0  # noqa: E731
    eta = torch.tensor([tau_to_eta(t, est.dt_s) for t in THRESHOLDS_S])[None]
    with torch.inference_mode():
        expected = torch.sigmoid(net(to_t(prev), to_t(latest), eta))[0].numpy()
    np.testing.assert_allclose(got, expected, atol=1e-5)
