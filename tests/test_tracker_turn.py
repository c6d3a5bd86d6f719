"""The tracker's rules for a turn across the path (``TrackerConfig.turn_across``), on
synthetic regions from a pinhole projection of targets moving in closed form."""

import dataclasses
import math

import numpy as np

from controllers.evidence import in_path_evidence
from controllers.geofence_config import GeofenceConfig
from controllers.path_prediction import Odometry, PathPrediction
from controllers.tracker import BlobTracker, TrackerConfig
from tests.test_tracker import SPEED_MPS, THRESHOLDS_S, _blob, _cal, _closing, _run

OFF = TrackerConfig(turn_across=False)


def test_a_track_that_crosses_the_centre_keeps_the_side_it_came_from():
    # an adult from 3 m left (camera x -3.0) walking right at 1.2 m/s, 0.5 m wide: when the
    # ego arrives (2.7 s) it stands in the path's right half; its region lies across the
    # image centre from job 21 to 25
    on, off = _run(-3.0, 1.2, jobs=26), _run(-3.0, 1.2, jobs=26, cfg=OFF)
    assert all(on[21:26])  # predicted on by its leading edge
    assert not any(off[21:26])  # across the centre: the corridor rule's alone
    assert on[:21] == off[:21]


def test_association_takes_the_ego_s_rotation_out():
    # a region standing still in the world while the ego turns left at 0.5 rad/s: it moves
    # right by fx * 0.05 rad (about 9 px) a job, more than its gate (6 px)
    cal = _cal()
    counts = {}
    for cfg in (TrackerConfig(), OFF):
        tracker, odo = BlobTracker(cfg, cal), Odometry()
        for k in range(6):
            t = 0.1 * k
            pose = odo.update(t, SPEED_MPS, 0.5)
            u = 60.0 + cal.fx_px * pose[2]
            tracker.update(t, pose, SPEED_MPS, [_blob_at(cal, u, 10.0)])
        counts[cfg.turn_across] = len(tracker.tracks)
    assert counts == {True: 1, False: 3}  # without: a new track each job (two missed kept)


def _blob_at(cal, u_left_px, width_px):
    return dataclasses.replace(_blob(cal, -1.5, -1.0, 20.0, 2.0), u_left=u_left_px, u_right=u_left_px + width_px)


def _floating(x0_m, vx_mps, v_along_mps, floating):
    return _closing(TrackerConfig(), v_along_mps, x0_m, vx_mps, floating=floating, jobs=12)


def test_a_floating_region_predicts_only_as_oncoming_traffic_in_its_lane():
    # crossing sideways at 4 m/s from 14 m right: in the path when the ego arrives (3.6 s),
    # but a floating region that does not come towards the ego predicts nothing
    assert _floating(14.0, -4.0, 0.0, floating=False)
    assert not _floating(14.0, -4.0, 0.0, floating=True)
    # oncoming at 8 m/s, drifting 0.9 m/s towards the path from 2 m right: its drift is
    # taken out, it keeps its lane
    assert _floating(2.0, -0.9, 8.0, floating=False)
    assert not _floating(2.0, -0.9, 8.0, floating=True)
    # oncoming in the ego's path, right half: predicted either way
    assert _floating(0.3, 0.0, 8.0, floating=True)
    # along the ego's heading at least float_closing_mps (2 m/s) towards it
    assert not _floating(0.3, 0.0, 1.0, floating=True)
    assert _floating(0.3, 0.0, 3.0, floating=True)


def test_a_track_across_the_centre_for_the_whole_window_keeps_its_side():
    # 0.8 m wide, from 2 m left at 0.8 m/s: across the centre from job 15, its
    # leading edge 1 m right of the path's centre when the ego arrives (2.7 s); from job
    # 20 every region of the 6-job window lies across the centre
    cal, cfg = _cal(), TrackerConfig(min_speed_mps=0.5)
    tracker, odo = BlobTracker(cfg, cal), Odometry()
    for k in range(25):
        t = 0.1 * k
        pose = odo.update(t, SPEED_MPS, 0.0)
        z, x = 30.0 - SPEED_MPS * t, -2.0 + 0.8 * t
        (track,) = tracker.update(t, pose, SPEED_MPS, [_blob(cal, x, x + 0.8, z, z / SPEED_MPS)])
        if k >= 20:
            assert all(o.u_left <= cal.cx_px <= o.u_right for o in track.obs)
            assert track.side(cal, True) is True  # the last region beside the centre: left
            assert tracker.in_path(track, t, pose, SPEED_MPS, 0.0)
    off = BlobTracker(TrackerConfig(min_speed_mps=0.5, turn_across=False), cal)
    assert not off.in_path(track, t, pose, SPEED_MPS, 0.0)  # across the centre: no side, no prediction


def _observed(turn_across: bool, rows: slice) -> list:
    """(left column, floating) of the regions ``observe`` keeps of a box inside every fence
    on ``rows``, over the counted rows 40-89, the ground around it outside every fence."""
    cal = _cal()
    h, w = cal.height_px, cal.width_px
    thr = np.asarray(THRESHOLDS_S)
    maps = np.zeros((len(thr), h, w), np.float32)
    maps[:, rows, 150:160] = 1.0
    bands = [np.zeros((h, w), bool) for _ in thr]
    for b in bands:
        b[40:90] = True
    tracker = TrackerConfig(turn_across=turn_across, predict_unchecked=True)
    paths = PathPrediction(GeofenceConfig(thresholds_s=THRESHOLDS_S, tracker=tracker), {"wide": cal})
    paths.start_job(0.0, SPEED_MPS, 0.0)
    paths.observe("wide", maps, thr, bands, SPEED_MPS, 0.0)
    return [(blob.u_left, track.floating) for blob, track in paths._seen["wide"]]


def test_observe_keeps_a_floating_region_and_judges_its_height_where_it_stands():
    # 15 rows, ending 30 rows above the counted rows' lowest row (89)
    assert _observed(True, slice(45, 60)) == [(150, True)]
    assert _observed(False, slice(45, 60)) == []
    # 6 rows: short for 0.5 m at the 0.8 s fence's static depth (8.9 m: 10 rows), tall
    # enough at the depth of the ground under it (row 58: 22 m, 4 rows)
    assert _observed(True, slice(52, 58)) == [(150, True)]
    # standing on the lowest counted rows: kept either way, not floating
    assert _observed(False, slice(70, 90)) == _observed(True, slice(70, 90)) == [(150, False)]


def _floating_box_evidence(turn_across: bool, top: int = 45, rows: int = 10, cols: int = 10) -> tuple[int, int]:
    """Counted in-path pixels of a predicted region floating above every fence's counted
    rows (the road beneath an oncoming car); each fence counts it, its size the region's."""
    cal = _cal()
    thr = np.asarray(THRESHOLDS_S)
    h, w = cal.height_px, cal.width_px
    maps = np.zeros((len(thr), h, w), np.float32)
    # at the largest fence's static depth (31 m) 0.3 m^2 covers 10 px and 0.5 m spans 2.9 rows
    maps[:, top : top + rows, 150 : 150 + cols] = 1.0
    bands = [np.zeros((h, w), bool) for _ in thr]
    for b in bands:
        b[40:90] = True
    predicted = maps[0] > 0.5
    cfg = GeofenceConfig(thresholds_s=THRESHOLDS_S, tracker=TrackerConfig(turn_across=turn_across))
    sizes, counted, _ = in_path_evidence(maps, thr, bands, cal, cfg, SPEED_MPS, 0.0, predicted, 0.5, static=False)
    assert set(sizes.tolist()) <= {0, int(counted.sum())}  # the size is the region's pixels
    return int(counted.sum()), int((sizes > 0).sum())


def test_a_predicted_region_counts_without_reaching_the_lowest_counted_rows():
    assert _floating_box_evidence(True) == (100, 4)  # in every fence, the smallest's need waived
    assert _floating_box_evidence(False) == (0, 0)
    # one that stands there counts either way; without the rules only where it is big enough
    assert _floating_box_evidence(False, top=80) == (100, 3)
    assert _floating_box_evidence(True, top=80) == (100, 4)
    # smaller than a face at the largest fence's depth, or shorter than 0.5 m there: nothing
    assert _floating_box_evidence(True, rows=4, cols=2) == (0, 0)
    assert _floating_box_evidence(True, rows=2, cols=50) == (0, 0)


def test_turn_across_settings_are_checked():
    import pytest

    with pytest.raises(ValueError, match="float_closing_mps"):
        TrackerConfig(float_closing_mps=-1.0)
    with pytest.raises(ValueError, match="float_closing_mps"):
        TrackerConfig(float_closing_mps=math.nan)


def test_a_floating_track_keeps_the_lane_of_the_heading_it_was_first_seen_at():
    # the ego turns left at 0.5 rad/s; a region standing still in the world is tracked
    # over the turn: its lane is the heading at its first region, not the ego's now
    cal = _cal()
    tracker, odo = BlobTracker(TrackerConfig(), cal), Odometry()
    for k in range(6):
        t = 0.1 * k
        pose = odo.update(t, SPEED_MPS, 0.5)
        (track,) = tracker.update(t, pose, SPEED_MPS, [_blob_at(cal, 60.0 + cal.fx_px * pose[2], 10.0)])
    assert track.first_psi == 0.0 and pose[2] > 0.2
