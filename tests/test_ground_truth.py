"""Per-pixel ground truth against closed forms (constant speeds, zero pitch)."""

import numpy as np
import pytest

from sim.camera import CameraConfig
from sim.episode import ScenarioSim
from sim.vehicles import EGO_SIZE_M
from tests.helpers import case

# camera on the front bumper, looking straight ahead: the camera plane is the bumper plane
CAM = CameraConfig(pitch_deg=0.0, mount_forward_m=EGO_SIZE_M[0] / 2, mount_height_m=1.0)


def two_frames(c, n_frames: int = 5):
    sim = ScenarioSim(c, CAM, seed=0, render=True)
    sim.reset()
    frames = [sim.capture()]
    for _ in range(n_frames):
        for _ in range(sim.n_sub):
            sim.substep(0.0)
        frames.append(sim.capture())
    gt = sim.ground_truth(frames[-2], frames[-1])
    truth = sim.truth()
    sim.close()
    return gt, truth, frames[-1]


def rear_face(gt):
    """Pixels of the target's rear face: instance 1 at its smallest depth."""
    m = gt.valid & (gt.instance == 1)
    z = gt.depth_m[m].min()
    return m & (gt.depth_m < z + 0.02)


@pytest.mark.parametrize("ego_kph,target_kph", [(50, 0), (72, 20), (30, 0)])
def test_fronto_parallel_target_tau_is_gap_over_closing_speed(ego_kph, target_kph):
    gt, truth, _ = two_frames(case(ego_kph, [{"vehicle": "gvt", "speed_kph": target_kph, "headway_m": 30}]))
    gap, v = truth.actors[0].gap_m, (ego_kph - target_kph) / 3.6
    face = rear_face(gt)
    assert face.sum() > 20
    np.testing.assert_allclose(gt.tau_s[face], gap / v, rtol=0.005)
    # eta consistent with tau and the frame interval: eta = tau / (tau + dt)
    np.testing.assert_allclose(gt.eta[face], (gap / v) / (gap / v + CAM.dt_s), rtol=1e-5)
    # depth of the rear face equals the bumper gap
    np.testing.assert_allclose(gt.depth_m[face], gap, rtol=1e-3)
    assert truth.actors[0].ttc_s == pytest.approx(gap / v, rel=1e-9)


def test_static_world_tau_is_depth_over_ego_speed():
    gt, _, _ = two_frames(case(60, []))
    static = gt.valid & (gt.instance == 0)
    assert static.sum() > 1000
    np.testing.assert_allclose(gt.tau_s[static], gt.depth_m[static] / (60 / 3.6), rtol=1e-4)


def test_receding_target_has_negative_tau():
    gt, truth, _ = two_frames(case(40, [{"vehicle": "car", "speed_kph": 80, "headway_m": 15}], threat=False))
    m = gt.valid & (gt.instance == 1)
    assert m.sum() > 20 and (gt.tau_s[m] < 0).all() and (gt.eta[m] > 1).all()
    assert truth.actors[0].ttc_s == np.inf


def test_static_flow_matches_projection_of_ego_motion():
    gt, _, _ = two_frames(case(54, []))
    fx, fy, cx, cy = CAM.intrinsics()
    H, W = gt.depth_m.shape
    v, u = np.mgrid[0:H, 0:W].astype(np.float64)
    Z1 = gt.depth_m.astype(np.float64)
    X1, Y1 = (u - cx) / fx * Z1, (v - cy) / fy * Z1
    Z0 = Z1 + (54 / 3.6) * CAM.dt_s  # the camera moved forward along its optical axis
    flow_u = u - (fx * X1 / Z0 + cx)
    flow_v = v - (fy * Y1 / Z0 + cy)
    m = gt.valid & (gt.instance == 0)
    np.testing.assert_allclose(gt.flow_px[..., 0][m], flow_u[m], atol=1e-3)
    np.testing.assert_allclose(gt.flow_px[..., 1][m], flow_v[m], atol=1e-3)


def test_sky_is_invalid_and_maps_have_documented_types():
    gt, _, frame = two_frames(case(50, []), n_frames=1)
    assert gt.eta.dtype == np.float32 and gt.tau_s.dtype == np.float32 and gt.flow_px.shape == (*gt.eta.shape, 2)
    assert frame.image.dtype == np.uint8 and frame.image.shape == (CAM.height_px, CAM.width_px, 3)
    sky = gt.instance < 0
    assert sky.any() and not gt.valid[sky].any()
