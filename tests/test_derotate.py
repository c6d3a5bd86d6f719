"""Derotation of a pair: a pure rotation's homography against the renderer's own cameras."""

import math

import numpy as np
import pytest

from controllers.base import Calibration
from controllers.derotate import derotate, rotation_homography
from sim.camera import CameraConfig, cam_T_ego
from sim.ground_truth import camera_pose


@pytest.mark.parametrize("view", ["wide", "fovea"])
@pytest.mark.parametrize("yaw", [0.05, -0.1, 0.138])
def test_far_points_land_where_the_turned_camera_sees_them(view, yaw):
    cam = CameraConfig(fovea_zoom=4.0)
    pin, cal = cam.view(view), Calibration.from_camera(cam, (4.5, 1.8)).views[view]
    T = cam_T_ego(cam)
    before, after = (0.0, 0.0, 0.3), (0.5, 0.1, 0.3 + yaw)  # the ego turned by yaw and moved 0.5 m
    ahead = 0.3 + yaw / 2
    world = np.array(
        [[2000 * math.cos(ahead + a), 2000 * math.sin(ahead + a), h, 1.0] for a in (-0.04, 0.0, 0.04) for h in (0, 40)]
    )
    uv0 = pin.project((camera_pose(T, before) @ world.T)[:3].T)
    uv1 = pin.project((camera_pose(T, after) @ world.T)[:3].T)
    H = rotation_homography(cal, yaw)
    q = (H @ np.c_[uv0, np.ones(len(uv0))].T).T
    moved = np.abs(uv1 - uv0).max()
    assert moved > 8.0  # the rotation moves them far
    assert np.abs(q[:, :2] / q[:, 2:] - uv1).max() < 0.1  # the homography takes it out


def test_no_rotation_is_the_frame_itself_and_the_unseen_strip_is_the_latest():
    cal = Calibration.from_camera(CameraConfig(), (4.5, 1.8))
    rng = np.random.default_rng(0)
    prev = rng.integers(0, 255, (cal.height_px, cal.width_px, 3), dtype=np.uint8)
    latest = rng.integers(0, 255, prev.shape, dtype=np.uint8)
    assert derotate(prev, latest, cal, 0.0) is prev
    out = derotate(prev, latest, cal, 0.1)  # a left turn: the scene moves right, the left strip is new
    assert np.array_equal(out[:, :5], latest[:, :5])
    assert not np.array_equal(out[:, -40:], latest[:, -40:])
