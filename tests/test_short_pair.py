"""The fovea's smallest fence read on the pair one frame apart too
(``GeofenceConfig.fovea_short_pair``): the estimator reads each threshold on its own
earlier frame in one call, the controller joins the two readings, and the loop hands over
the frame and prices it."""

import dataclasses

import numpy as np
import pytest
import torch

from bittc_core.errors import ConfigError
from bittc_core.estimator import BittcEstimator, EstimatorInputError, FlowEstimator
from bittc_core.model import BinaryTTCNet, get_config
from controllers.base import Observation
from controllers.geofence import GeofenceConfig, GeofenceController
from tests.geofence_maps import CAM, FOVEA_CAL, SPEED, THR, ViewMapEstimator, fovea_box, road

H, W = 48, 96


def frames(n, seed=0):
    """A smooth texture zoomed in a little more each frame (an approach)."""
    import cv2

    base = cv2.resize(np.random.default_rng(seed).integers(0, 256, (H // 4, W // 4, 3), dtype=np.uint8), (W, H))
    c = ((W - 1) / 2, (H - 1) / 2)
    return [cv2.warpAffine(base, cv2.getRotationMatrix2D(c, 0.0, 1 + 0.03 * i), (W, H)) for i in range(n)]


@pytest.mark.parametrize("tta", ["none", "flip"])
def test_the_network_reads_each_threshold_on_its_own_pair_as_separate_calls_would(tta):
    torch.manual_seed(0)
    net = BinaryTTCNet(dataclasses.replace(get_config("tiny"), corr_groups=4))  # the correlation volume too
    est = BittcEstimator(net, device=torch.device("cpu"), tta=tta)
    a, _, b, c = frames(4)
    joint = est.geofence_pairs([b, a, a], c, [1.0, 0.5, 2.0])
    assert joint.shape == (3, H, W)
    assert np.abs(joint[0] - est.geofence(b, c, [1.0])[0]).max() < 1e-6
    assert np.abs(joint[1:] - est.geofence(a, c, [0.5, 2.0])).max() < 1e-6
    assert np.abs(joint[0] - est.geofence(a, c, [1.0])[0]).max() > 1e-5  # the pair matters (an untrained net)


def test_each_frame_goes_through_the_extractor_once_when_every_frame_has_a_job():
    """The longer pair's frames first, then the shorter pair's, as the controller reads them
    and the loop's cache model counts them: the cache still holds every earlier frame."""
    torch.manual_seed(0)
    est = BittcEstimator(BinaryTTCNet(get_config("tiny")), device=torch.device("cpu"))
    f = frames(13)
    for k in range(3, 13):
        est.geofence_pairs([f[k - 3], f[k - 3], f[k - 1]], f[k], [0.5, 1.0, 1.5])
    assert est.feature_computations == 13


def test_other_estimators_read_one_pair_a_call_and_a_mismatch_is_refused():
    a, b, c = frames(3)
    flow = FlowEstimator()
    joint = flow.geofence_pairs([b, a], c, [1.0, 0.6])
    assert np.array_equal(joint[0], flow.geofence(b, c, [1.0])[0])
    assert np.array_equal(joint[1], flow.geofence(a, c, [0.6])[0])
    with pytest.raises(EstimatorInputError, match="2 earlier frames for 1 thresholds"):
        flow.geofence_pairs([b, a], c, [1.0])
    # a controller on such an estimator would pay a whole call for the shorter pair: refused
    with pytest.raises(ConfigError, match="fovea_short_pair: estimator 'flow'"):
        GeofenceController(flow, GeofenceConfig(fovea_short_pair=True))


class PairMapEstimator(ViewMapEstimator):
    """Hard fences of the true TTC maps: the wide view's ``tau``, the fovea's ``tau_fovea``
    on the pair 0.3 s apart (its earlier frame marked 3) and ``tau_short`` on the pair one
    frame apart (marked 1); thresholds in the 0.1 s time base, so times the pair's frames."""

    sources_per_threshold = True  # reads every pair of a job in one call, as the network does

    def geofence(self, prev, latest, thresholds_s):
        frames_apart = int(prev[0, 0, 1]) or 3
        tau = self.tau if latest[0, 0, 0] == 0 else self.tau_short if frames_apart == 1 else self.tau_fovea
        t = np.asarray(thresholds_s)[:, None, None] * frames_apart
        return ((tau > 0) & (tau <= t)).astype(np.float32)

    def geofence_pairs(self, prevs, latest, thresholds_s):
        return np.concatenate([self.geofence(p, latest, [t]) for p, t in zip(prevs, thresholds_s)])


def run_fovea(short_pair: bool, give_short: bool = True, jobs: int = 3):
    est = PairMapEstimator()
    # a car 33 m ahead closing faster than the ego: inside the 2.8 s fence on either pair,
    # inside the 1.84 s fence only on the shorter one
    est.tau, est.tau_fovea, est.tau_short = road(), fovea_box(33.0, 2.5), fovea_box(33.0, 1.7)
    ctrl = GeofenceController(est, GeofenceConfig(thresholds_s=THR, fovea_short_pair=short_pair))
    assert not GeofenceConfig().fovea_short_pair  # off by default
    ctrl.reset(FOVEA_CAL)
    wide = np.zeros((CAM.height_px, CAM.width_px, 3), np.uint8)
    latest, prev, short = wide.copy(), wide.copy(), wide.copy()
    latest[0, 0, 0], prev[0, 0, 1], short[0, 0, 1] = 1, 3, 1
    obs = [
        Observation(
            0.1 * k, SPEED, wide, wide, 0.3, FOVEA_CAL, latest, prev, fovea_prev_short=short if give_short else None
        )
        for k in range(jobs)
    ]
    return ctrl, [ctrl.act(o, None) for o in obs]


def test_the_fovea_s_smallest_fence_fires_on_the_shorter_pair_and_costs_one_threshold():
    ctrl, cmds = run_fovea(short_pair=True)
    assert ctrl.view_thresholds == {"wide": 4, "fovea": 3}
    last = cmds[-1].telemetry
    assert last["short_pair"] == "fovea" and last["fired_view"] == "fovea" and last["fence_fired_s"] == THR[2]
    assert last["inpath_px_fovea_1.8s"] > 100
    for short_pair, give_short in ((False, True), (True, False)):  # off, or no such frame: the 0.3 s pair alone
        ctrl, cmds = run_fovea(short_pair, give_short)
        last = cmds[-1].telemetry
        assert last["short_pair"] == "" and last["fence_fired_s"] == THR[3] and last["inpath_px_fovea_1.8s"] == 0


def test_the_loop_hands_over_the_fovea_one_frame_back():
    import scenarios
    from controllers.base import BrakeCommand, Controller
    from sim.camera import CameraConfig
    from sim.latency import parse_latency
    from sim.runner import run_case

    class Seen(Controller):
        name = "seen"
        needs_camera = True
        estimator_kind = "bittc"
        num_alphas = 1

        def __init__(self, stride):
            self.frame_stride, self.obs = stride, []

        def act(self, obs, truth):
            self.obs.append(obs)
            return BrakeCommand()

    case = scenarios.resolve("CCRs-20")[0]
    for stride in (3, 1):
        ctrl = Seen(stride)
        run_case(case, ctrl, CameraConfig(fovea_zoom=4.0), 0, latency=parse_latency("fixed:0"))
        obs = ctrl.obs[:6]
        if stride == 1:  # the pair itself is one frame apart
            assert all(o.fovea_prev_short is None and o.short_pair_yaw_rad is None for o in obs)
            continue
        for before, o in zip(obs, obs[1:]):  # every frame processed: the job before saw it as its latest
            assert np.array_equal(o.fovea_prev_short, before.fovea_latest) and o.short_pair_yaw_rad == 0.0
            assert not np.array_equal(o.fovea_prev_short, o.fovea_prev)


def test_a_profile_charges_the_shorter_pair_as_one_threshold_and_its_frame_once(tmp_path):
    import controllers
    import scenarios
    from sim.camera import CameraConfig
    from sim.latency import JobWork, named_profiles, parse_latency
    from sim.runner import run_case

    prof = named_profiles()["this-cpu"]
    ctrl = controllers.make("geofence", thresholds_s=(1.0, 2.0), fovea_short_pair=True)  # the fovea: its 2 s fence
    s = run_case(
        scenarios.resolve("CCRs-20")[0],
        ctrl,
        CameraConfig(fovea_zoom=2.0),
        0,
        tmp_path / "r",
        latency=parse_latency("profile:this-cpu"),
    )
    rows = (tmp_path / "r" / "trace.csv").read_text().splitlines()
    col, short = rows[0].split(",").index("latency_ms"), rows[0].split(",").index("short_pair")
    lat = {float(r.split(",")[col]) for r in rows[1:] if r.split(",")[col]}
    assert {r.split(",")[short] for r in rows[1:] if r.split(",")[col]} == {"fovea"}
    # the fovea (half as wide: its thresholds and extractions count half) reads its 2 s fence on two pairs
    steady = prof.latency_ms(JobWork("bittc", 2, 2 + 0.5 * 2, 1 + 0.5))  # one new frame per view
    first = prof.latency_ms(JobWork("bittc", 2, 2 + 0.5 * 2, 2 + 1))  # both frames of the first pairs
    # the first job (frame 3) also extracts the fovea's frame 2, which no job had used; so the
    # job on frame 5, whose pair is (2, 5), finds frame 2 in the fovea's cache, not the wide view's
    very_first = prof.latency_ms(JobWork("bittc", 2, 2 + 0.5 * 2, 2 + 1 + 0.5))
    third = prof.latency_ms(JobWork("bittc", 2, 2 + 0.5 * 2, 2 + 0.5))
    expected = {round(x, 2) for x in (steady, first, very_first, third)}
    assert lat == expected and s["frames_skipped"] == 0
