"""The tracker predicts which fenced regions enter the ego's path (synthetic regions from a
pinhole projection of targets moving in closed form)."""

import dataclasses

import numpy as np
import pytest

from controllers.base import Calibration
from controllers.evidence import Blob, ground_ttc_map
from controllers.path_prediction import Odometry
from controllers.road import ground_ttc_per_row
from controllers.tracker import BlobTracker, TrackerConfig
from sim.camera import CameraConfig
from sim.vehicles import EGO_SIZE_M

THRESHOLDS_S = (0.8, 1.2146, 1.8442, 2.8)
SPEED_MPS = 40 / 3.6


def _cal() -> Calibration:
    return Calibration.from_camera(CameraConfig(pitch_deg=0.0), EGO_SIZE_M)


def _blob(cal, x_left_m, x_right_m, depth_m, tau_s):
    u = [cal.cx_px + cal.fx_px * x / depth_m for x in (x_left_m, x_right_m)]
    bound = next((t for t in THRESHOLDS_S if t >= tau_s), THRESHOLDS_S[-1])
    mask = np.zeros((cal.height_px, cal.width_px), bool)
    return Blob(mask, max(u[0], 0.0), min(u[1], cal.width_px - 1.0), bound)


def _run(lateral_m, lateral_speed_mps, width_m=0.5, depth0_m=30.0, jobs=12, cfg=None):
    """In-path predictions of a target whose left edge is at ``lateral_m`` (camera x, + right)
    moving at ``lateral_speed_mps`` across a straight ego's path, job by job."""
    cal = _cal()
    tracker, odo = BlobTracker(cfg or TrackerConfig(), cal), Odometry()
    out = []
    for k in range(jobs):
        t = 0.1 * k
        pose = odo.update(t, SPEED_MPS, 0.0)
        z = depth0_m - SPEED_MPS * t  # camera depth: the ego closes at its speed
        x = lateral_m + lateral_speed_mps * t
        blob = _blob(cal, x, x + width_m, z, z / SPEED_MPS)
        (track,) = tracker.update(t, pose, SPEED_MPS, [blob])
        out.append(tracker.in_path(track, t, pose, SPEED_MPS, 0.0))
    return out


def _closing(cfg, v_along_mps, x0_m, vx_mps=0.0, floating=True, no_ground=(), cut_from=None, jobs=8, depth0_m=40.0):
    """Whether the tracker predicts into the path, at the last job, a target 1.8 m wide
    whose left edge starts ``x0_m`` right of the camera (camera x), coming towards the ego
    along its heading at ``v_along_mps`` and moving right at ``vx_mps``, its region
    ``floating`` or standing. The ground under it shows (its depth known) but in the jobs
    ``no_ground``; from job ``cut_from`` on its region runs out of the image's right side."""
    cal = _cal()
    tracker, odo = BlobTracker(cfg, cal), Odometry()
    closing = SPEED_MPS + v_along_mps
    for k in range(jobs):
        t = 0.1 * k
        pose = odo.update(t, SPEED_MPS, 0.0)
        z, x = depth0_m - closing * t, x0_m + vx_mps * t
        ground = None if k in no_ground else z
        blob = dataclasses.replace(_blob(cal, x, x + 1.8, z, z / closing), contact_depth_m=ground)
        if cut_from is not None and k >= cut_from:
            blob = dataclasses.replace(blob, u_right=cal.width_px - 1.0)
        (track,) = tracker.update(t, pose, SPEED_MPS, [blob])
        track.floating = floating
    return tracker.in_path(track, t, pose, SPEED_MPS, 0.0)


def test_a_pedestrian_stepping_into_the_path_is_predicted_in_path_once_tracked():
    # from 3.5 m right at 1.4 m/s: at the ego's arrival (2.7 s) it is in the middle of the path
    pred = _run(3.5, -1.4)
    assert pred[:2] == [False, False]  # fewer than min_hits regions: no prediction
    assert all(pred[3:])


def test_a_standing_pedestrian_beside_the_path_is_not():
    assert not any(_run(3.0, 0.0))


def test_a_pedestrian_walking_away_from_the_path_is_not():
    assert not any(_run(-1.2, -1.4))


def test_a_pedestrian_that_clears_before_the_ego_arrives_is_not():
    # from 2 m right at 2.5 m/s: through the path and 4.7 m left of it when the ego arrives
    assert not any(_run(2.0, -2.5)[4:])


def test_a_crossing_car_whose_front_has_passed_is_in_path_by_its_body():
    # a 4.5 m car from 16 m right at 8 m/s: at the ego's arrival (2.7 s) its front is 5.6 m
    # left of the path's centre and its body still across the path
    assert any(_run(16.0, -8.0, width_m=4.5, jobs=20, cfg=TrackerConfig(extent=True)))
    # its front edge alone, a point, has crossed the path before the ego arrives
    assert not any(_run(16.0, -8.0, width_m=4.5, jobs=20))


def test_a_region_cut_by_the_image_side_is_judged_by_its_inner_edge():
    # a long target whose right part lies beyond the image's side, front coming in: its
    # outer edge moves with the cut, its inner edge shows where it goes
    assert any(_run(6.0, -2.6, width_m=40.0, cfg=TrackerConfig(cut_regions=True)))
    assert any(_run(6.0, -2.6, width_m=40.0, cfg=TrackerConfig(extent=True)))
    assert not any(_run(6.0, -2.6, width_m=40.0))  # by default a cut region predicts nothing
    # the same region moving out never is
    assert not any(_run(6.0, 1.0, width_m=40.0, cfg=TrackerConfig(cut_regions=True)))
    assert not any(_run(6.0, 1.0, width_m=40.0, cfg=TrackerConfig(extent=True)))


def test_the_corridor_allowance_lets_in_an_edge_that_lands_inside_the_corridor():
    # from 3 m right at 1 m/s: at the ego's arrival its left edge is 0.3 m right of the
    # path's centre, so its bearing moves out, slowly, all the way in
    assert any(_run(3.0, -1.0))
    assert not any(_run(3.0, -1.0, cfg=TrackerConfig(corridor_allowance=False, bearing_tol_px_per_s=0.0)))
    # a standing target beside the path moves out faster than the allowance
    assert not any(_run(2.0, 0.0))
    # a region wider than a road user (scenery cut at a fence's static depth) has no allowance
    assert not any(_run(3.0, -1.0, width_m=6.0, cfg=TrackerConfig(bearing_tol_px_per_s=0.0)))


def test_ground_ttc_map_is_the_straight_road_rule_without_yaw():
    cal = Calibration.from_camera(CameraConfig(), EGO_SIZE_M)
    straight = ground_ttc_map(cal, SPEED_MPS, 0.0)
    np.testing.assert_array_equal(straight, np.repeat(ground_ttc_per_row(cal, SPEED_MPS)[:, None], cal.width_px, 1))
    # turning left, the ground on the right approaches sooner (dZ/dt = -(s cos p + w X))
    turning = ground_ttc_map(cal, SPEED_MPS, 0.4)
    row = int(np.flatnonzero(np.isfinite(straight[:, 0]))[0]) + 5
    assert turning[row, -1] < straight[row, -1] and turning[row, 0] > straight[row, 0]


def test_tracker_config_is_checked():
    with pytest.raises(ValueError):
        TrackerConfig(min_hits=1)
