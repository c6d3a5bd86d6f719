"""``geofence-exact``: the geofence policy on the exact fences of the ground truth."""

import numpy as np
import pytest

import controllers
import scenarios
from controllers.geofence_config import estimator_thresholds
from controllers.geofence_exact import ExactFences, pair_eta
from sim.camera import CameraConfig
from sim.latency import parse_latency
from sim.runner import run_case


@pytest.mark.parametrize("stride", [1, 3])
def test_a_pixel_lies_inside_an_exact_fence_exactly_when_its_ttc_is_below_it(stride):
    tau = np.array([[0.5, 1.49, 1.51, 3.0], [np.inf, -2.0, 2.9, 1.0]], dtype=np.float32)  # [s]
    est = ExactFences()
    est.set_ground_truth(pair_eta(tau, 0.1 * stride))
    thr = np.array([1.5, 2.8])  # [s] camera plane
    img = np.zeros((2, 4, 3), np.uint8)
    maps = est.geofence(img, img, estimator_thresholds(est, thr, 0.1, stride))
    expect = np.stack([(tau > 0) & (tau <= t) for t in thr])
    np.testing.assert_array_equal(maps > 0.5, expect)


def test_it_needs_the_per_pixel_truth_and_is_priced_as_the_network():
    ctrl = controllers.make("geofence-exact", thresholds_s=(1.0, 2.0))
    assert ctrl.uses_pixel_truth and ctrl.estimator_kind == "bittc" and ctrl.cached_frames > 0
    assert "geofence-exact" in controllers.ESTIMATOR_CONTROLLERS


def test_exact_fences_brake_in_time_for_a_pedestrian_crossing_from_the_far_side():
    case = scenarios.resolve("CPFA-50-20")[0]
    latency = parse_latency("profile:this-cpu")
    exact = run_case(case, controllers.make("geofence-exact"), CameraConfig(fovea_zoom=4.0), seed=0, latency=latency)
    assert not exact["collision"] and exact["ttc_at_first_brake_s"] > 1.0
    assert 15.0 < exact["latency_ms_mean"] < 30.0  # the network's price, not the lookup's
