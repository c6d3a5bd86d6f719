"""A fenced region's parts (``controllers.evidence``) and the tracker's hold
(``controllers.path_prediction``), on hand-made masks: a road user counted in two fences
is one region, and a road user's prediction is held while its bearing comes in."""

import numpy as np

from controllers.evidence import Blob, fenced_blobs

H, W = 40, 60
THR = np.array([1.0, 2.0])  # [s]
DEPTH = np.linspace(100.0, 2.0, H)  # [m] a stand-in ground depth per row, nearer lower down


def _blobs(inside, lowest_rows, join_rows, maps=None):
    touch = np.zeros_like(inside)
    touch[max(lowest_rows) - 1 : max(lowest_rows) + 1] = True
    maps = np.stack([inside.astype(np.float32)] * len(THR)) if maps is None else maps
    return fenced_blobs(inside, touch, maps, THR, 0.5, 4, DEPTH, join_rows)


def test_a_road_user_counted_in_two_fences_with_rows_between_is_one_region():
    inside = np.zeros((H, W), dtype=bool)
    inside[10:18, 20:24] = True  # the upper body, counted in the larger fence
    inside[20:30, 21:25] = True  # the legs, counted in the smaller one, two rows lower
    joined = _blobs(inside, [29, 17], join_rows=3)
    assert len(joined) == 1 and (joined[0].u_left, joined[0].u_right) == (20.0, 24.0)
    assert joined[0].mask.sum() == inside.sum()
    # without joining, only the legs stand on the road's lowest rows: the upper body is lost
    apart = _blobs(inside, [29, 17], join_rows=0)
    assert len(apart) == 1 and apart[0].mask.sum() == 40
    # side by side parts stay apart
    inside[:] = False
    inside[20:30, 10:14] = True
    inside[20:30, 16:20] = True
    assert len(_blobs(inside, [29, 17], join_rows=3)) == 2


def _held(hold_jobs: int, in_path, closing=True, width_px: int = 4):
    """Which of the jobs' calls of ``predicted`` count a region whose track the tracker
    predicts into the path as ``in_path`` says, job by job."""
    from controllers.geofence import GeofenceConfig
    from controllers.path_prediction import PathPrediction
    from controllers.track import Obs, Track
    from controllers.tracker import TrackerConfig
    from tests.geofence_maps import CAL, SPEED

    cfg = GeofenceConfig(tracker=TrackerConfig(hold_jobs=hold_jobs, predict_unchecked=True))
    paths = PathPrediction(cfg, {"wide": CAL})
    mask = np.zeros((CAL.height_px, CAL.width_px), dtype=bool)
    mask[40:50, 200 : 200 + width_px] = True
    blob = Blob(mask, 200.0, 200.0 + width_px - 1, 1.5)
    track = Track(obs=[Obs(0.0, blob.u_left, blob.u_right, 1.5, None, SPEED, (0.0, 0.0, 0.0))])
    tracker, answers = paths.trackers["wide"], iter(in_path)
    tracker.in_path = lambda *args: next(answers)
    tracker.closing_in = lambda *args: closing
    out = []
    for k in range(len(in_path)):
        paths._seen["wide"] = [(blob, track)]
        out.append(bool(paths.predicted("wide", mask.shape, 0.1 * k, SPEED, 0.0).any()))
    return out


def test_a_road_user_s_prediction_is_held_while_its_bearing_still_closes_in():
    seq = [True, False, False, False, True, False]
    assert _held(0, seq) == seq
    assert _held(2, seq) == [True, True, True, False, True, True]
    assert _held(2, seq, closing=False) == seq  # its bearing moves out: nothing to hold
    assert _held(2, seq, width_px=120) == seq  # wider than a road user: scenery, not held
