"""Exact ground truth on road users' moving limbs: a pedestrian's swinging foot and a
bicycle's turning wheel, checked in both views against motions written out in closed form."""

import math

import numpy as np
import pytest

from sim.camera import CameraConfig, cam_T_ego
from sim.ground_truth import camera_pose, compute_ground_truth, part_motions
from sim.scenery import RoadConfig
from sim.vru import ADULT_HEIGHT_M, BICYCLE_LENGTH_M, BICYCLE_WHEEL_RADIUS_M, LEG_SWING_DEG, part_poses, vru_spec
from sim.world import World

DT_S = 0.1
EGO_SPEED_MPS = 8.0


def _rz(h):
    c, s = math.cos(h), math.sin(h)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])


def _ry(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _pose(R, t):
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, t
    return T


def left_leg_pose(x, y, heading, travelled):
    """world_T_leg of an adult's left leg, written out: the hip at 0.52 h, 0.06 h to the
    left; the leg swings by -25 deg * sin(2 pi d / (0.8 h)) about the body's y axis."""
    h = ADULT_HEIGHT_M
    swing = -math.radians(LEG_SWING_DEG) * math.sin(2 * math.pi * travelled / (0.8 * h))
    hip = np.array([x, y, 0.0]) + _rz(heading) @ np.array([0.0, 0.06 * h, 0.52 * h])
    return _pose(_rz(heading) @ _ry(swing), hip)


def front_wheel_pose(x, y, heading, travelled):
    """world_T_wheel of the front wheel: the axle 0.6 m ahead of the centre at the wheel's
    radius, rolled by travelled / radius about the axle (the top moving forward)."""
    r = BICYCLE_WHEEL_RADIUS_M
    axle = np.array([x, y, 0.0]) + _rz(heading) @ np.array([BICYCLE_LENGTH_M / 2 - r, 0.0, r])
    return _pose(_rz(heading) @ _ry(travelled / r), axle)


def _closed_form(depth, pix, K, cam1, cam0, T1, T0):
    """(eta, flow (N, 2) [px]) of the points seen at pixels ``pix`` (rows, cols) that move
    rigidly from T0 to T1."""
    v, u = pix
    Z1 = depth[v, u].astype(np.float64)
    p_c1 = np.stack([(u - K[0, 2]) / K[0, 0] * Z1, (v - K[1, 2]) / K[1, 1] * Z1, Z1, np.ones_like(Z1)])
    p_w1 = np.linalg.inv(cam1) @ p_c1
    p_w0 = T0 @ np.linalg.inv(T1) @ p_w1
    p_c0 = cam0 @ p_w0
    u0 = K[0, 0] * p_c0[0] / p_c0[2] + K[0, 2]
    v0 = K[1, 1] * p_c0[1] / p_c0[2] + K[1, 2]
    return Z1 / p_c0[2], np.stack([u - u0, v - v0], axis=-1)


@pytest.fixture(scope="module")
def scene():
    cam = CameraConfig(height_px=96, width_px=288, fovea_zoom=4.0, fovea_width_share=1.0)
    world = World(cam, RoadConfig(x_end_m=150.0), seed=3)
    rng = np.random.default_rng(0)
    ped, bike = vru_spec("adult", rng), vru_spec("cyclist", rng)
    ped_id, ped_parts = world.add_vru(ped)
    bike_id, bike_parts = world.add_vru(bike)
    # the pedestrian crosses from the right 14 m ahead; the cyclist rides towards the camera
    ped_state = {0: (14.0, -1.0, math.pi / 2, 1.30), 1: (14.0, -1.0 + 0.15, math.pi / 2, 1.45)}
    bike_state = {0: (24.0, 0.8, math.pi, 3.0), 1: (24.0 - 0.5, 0.8, math.pi, 3.5)}
    cams = {k: camera_pose(cam_T_ego(cam), (k * EGO_SPEED_MPS * DT_S, 0.0, 0.0)) for k in (0, 1)}
    poses = {}
    for k in (0, 1):
        for pid, T in zip(ped_parts, part_poses(ped, ped_state[k][:3], ped_state[k][3])):
            poses.setdefault(k, {})[pid] = T
        for pid, T in zip(bike_parts, part_poses(bike, bike_state[k][:3], bike_state[k][3])):
            poses[k][pid] = T
    world.set_part_poses(ped_id, [poses[1][pid] for pid in ped_parts])
    world.set_part_poses(bike_id, [poses[1][pid] for pid in bike_parts])
    renders = {v: world.render(cams[1], pinhole=cam.view(v)) for v in ("wide", "fovea")}
    yield cam, renders, cams, poses, ped_parts, bike_parts, ped_state, bike_state
    world.close()


def test_part_poses_match_the_closed_form(scene):
    *_, poses, ped_parts, bike_parts, ped_state, bike_state = scene
    for k in (0, 1):
        np.testing.assert_allclose(poses[k][ped_parts[1]], left_leg_pose(*ped_state[k]), atol=1e-12)
        np.testing.assert_allclose(poses[k][bike_parts[1]], front_wheel_pose(*bike_state[k]), atol=1e-12)


@pytest.mark.parametrize("view", ["wide", "fovea"])
@pytest.mark.parametrize("what", ["foot", "wheel"])
def test_eta_and_tau_on_a_swinging_foot_and_a_wheel(scene, view, what):
    cam, renders, cams, poses, ped_parts, bike_parts, ped_state, bike_state = scene
    r = renders[view]
    K = cam.view(view).K()
    if what == "foot":
        part_id, T = ped_parts[1], {k: left_leg_pose(*ped_state[k]) for k in (0, 1)}
    else:
        part_id, T = bike_parts[1], {k: front_wheel_pose(*bike_state[k]) for k in (0, 1)}
    mask = r.part == part_id
    assert mask.sum() >= 3, f"the {what} covers {mask.sum()} px in the {view} view"
    if what == "foot":  # the lowest fifth of the leg's rows: the foot and ankle
        rows = np.flatnonzero(mask.any(axis=1))
        mask &= np.arange(mask.shape[0])[:, None] >= rows.max() - max(1, (rows.max() - rows.min()) // 5)
    gt = compute_ground_truth(
        r.depth_m, r.instance, K, cams[1], cams[0], part_motions(poses[0], poses[1]), DT_S, cam.far_m, parts=r.part
    )
    pix = np.nonzero(mask)
    want_eta, want_flow = _closed_form(r.depth_m, pix, K, cams[1], cams[0], T[1], T[0])
    np.testing.assert_allclose(gt.eta[pix], want_eta, rtol=2e-6)
    want_tau = DT_S * want_eta / (1 - want_eta)
    np.testing.assert_allclose(gt.tau_s[pix], want_tau, rtol=1e-4)
    np.testing.assert_allclose(gt.flow_px[pix], want_flow, atol=1e-3)
    # the limb's own motion matters: with the trunk's (or the frame's) the points move elsewhere
    trunk = ped_parts[0] if what == "foot" else bike_parts[0]
    _, wrong = _closed_form(r.depth_m, pix, K, cams[1], cams[0], poses[1][trunk], poses[0][trunk])
    assert np.max(np.abs(wrong - want_flow)) > 0.2
