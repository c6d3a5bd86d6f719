"""The tracker's rules for oncoming traffic (``TrackerConfig.oncoming``), on synthetic
regions of a car oncoming in the ego's path from a pinhole projection in closed form."""

import dataclasses

import numpy as np

from controllers.geofence_config import GeofenceConfig
from controllers.path_prediction import Odometry, PathPrediction
from controllers.tracker import BlobTracker, TrackerConfig
from tests.test_tracker import SPEED_MPS, THRESHOLDS_S, _blob, _cal

OFF = TrackerConfig(oncoming=False)


def _oncoming(cfg, v_mps=8.0, x0_m=0.3, vx_mps=0.0, no_ground=(), cut_from=None, jobs=8, depth0_m=40.0):
    """Whether the tracker predicts into the path, at the last job, a floating car 1.8 m
    wide whose left edge starts ``x0_m`` right of the camera, oncoming at ``v_mps`` along
    the ego's heading and moving right at ``vx_mps``. Jobs in ``no_ground`` show no ground
    under it (no contact depth); from job ``cut_from`` on its region runs out of the
    image's right side."""
    cal = _cal()
    tracker, odo = BlobTracker(cfg, cal), Odometry()
    closing = SPEED_MPS + v_mps
    for k in range(jobs):
        t = 0.1 * k
        pose = odo.update(t, SPEED_MPS, 0.0)
        z, x = depth0_m - closing * t, x0_m + vx_mps * t
        blob = _blob(cal, x, x + 1.8, z, z / closing)
        blob = dataclasses.replace(blob, contact_depth_m=None if k in no_ground else z)
        if cut_from is not None and k >= cut_from:
            blob = dataclasses.replace(blob, u_right=cal.width_px - 1.0)
        (track,) = tracker.update(t, pose, SPEED_MPS, [blob])
        track.floating = True
    return tracker.in_path(track, t, pose, SPEED_MPS, 0.0)


def test_an_oncoming_car_may_move_faster_than_a_road_user():
    # 17 m/s (60 km/h): above a road user's bound (15 m/s), within oncoming traffic's (40)
    assert _oncoming(TrackerConfig(), v_mps=17.0)
    assert not _oncoming(OFF, v_mps=17.0)
    assert _oncoming(OFF, v_mps=8.0)  # both predict a slower one
    assert not _oncoming(TrackerConfig(oncoming_max_speed_mps=16.0), v_mps=17.0)


def test_an_oncoming_car_is_placed_where_the_ground_under_it_shows():
    # the last two jobs show no ground under it: their depth would be the fence's TTC at
    # the ego's speed (11 m/s) instead of the car's closing speed (19 m/s), far too near
    gap = (6, 7)
    road_user_bound = TrackerConfig(oncoming_max_speed_mps=TrackerConfig().max_speed_mps)
    assert _oncoming(road_user_bound, no_ground=gap)
    assert not _oncoming(OFF, no_ground=gap)
    # it needs min_hits (3) jobs with the ground under it: two depths that err by metres
    # fit any motion
    assert _oncoming(TrackerConfig(), no_ground=tuple(range(5)))
    assert not _oncoming(TrackerConfig(), no_ground=tuple(range(6)))


def test_an_oncoming_car_cut_by_the_image_side_predicts_by_its_leading_edge():
    # from 1.5 m right, coming in at 1 m/s (the ego turning towards it), cut from job 4 on
    assert _oncoming(TrackerConfig(), x0_m=1.5, vx_mps=-1.0, cut_from=4)
    assert not _oncoming(OFF, x0_m=1.5, vx_mps=-1.0, cut_from=4)


def _fovea_predictions(oncoming: bool, standing: bool) -> list[bool]:
    """Per job, whether the fovea's regions count as predicted: a box inside every fence
    that comes nearer (down and wider) job by job, floating above the counted rows
    (``standing``: reaching their lowest row), in a camera whose two views are alike."""
    cal = _cal()
    h, w = cal.height_px, cal.width_px
    thr = np.asarray(THRESHOLDS_S)
    bands = [np.zeros((h, w), bool) for _ in thr]
    for b in bands:
        b[40:90] = True
    tracker = TrackerConfig(oncoming=oncoming)
    paths = PathPrediction(GeofenceConfig(thresholds_s=THRESHOLDS_S, tracker=tracker), {"wide": cal, "fovea": cal})
    out = []
    for k in range(8):
        t = 0.1 * k
        paths.start_job(t, SPEED_MPS, 0.0)
        maps = np.zeros((len(thr), h, w), np.float32)
        half = 6 + k  # [px] it grows as it nears, centred right of the image centre
        bottom = 60 + 2 * k if not standing else 89
        maps[:, 45 : bottom + 1, int(cal.cx_px) + 2 : int(cal.cx_px) + 2 + 2 * half] = 1.0
        for view in ("wide", "fovea"):
            paths.observe(view, maps, thr, bands, SPEED_MPS, t)
        out.append(bool(paths.predicted("fovea", (h, w), t, SPEED_MPS, 0.0).any()))
    return out


def test_the_fovea_predicts_its_floating_tracks_only():
    two_views = {"wide": _cal(), "fovea": _cal()}
    assert PathPrediction(GeofenceConfig(thresholds_s=THRESHOLDS_S), two_views).floating_only == ("fovea",)
    assert not any(_fovea_predictions(oncoming=False, standing=False))
    assert not any(_fovea_predictions(oncoming=True, standing=True))
    assert any(_fovea_predictions(oncoming=True, standing=False))
