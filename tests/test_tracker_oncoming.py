"""The tracker's rules for oncoming traffic (``TrackerConfig.oncoming``), on synthetic
regions of a car oncoming in the ego's path from a pinhole projection in closed form."""

import numpy as np

import tests.geofence_maps as gc
from controllers.evidence import fenced_blobs
from controllers.geofence_config import GeofenceConfig
from controllers.path_prediction import PathPrediction
from controllers.tracker import BlobTracker, TrackerConfig
from tests.test_tracker import SPEED_MPS, THRESHOLDS_S, _cal, _closing

OFF = TrackerConfig(oncoming=False)


def _oncoming(cfg, v_mps=8.0, x0_m=0.3, vx_mps=0.0, no_ground=(), cut_from=None):
    """A floating car 1.8 m wide oncoming at ``v_mps`` (``tests.test_tracker._closing``):
    predicted into the path at the last of 8 jobs?"""
    return _closing(cfg, v_mps, x0_m, vx_mps, floating=True, no_ground=no_ground, cut_from=cut_from)


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


def _judged_rows_40_to_89():
    """(calibration, thresholds [s], per fence the judged pixels: rows 40-89 of every column)."""
    cal = _cal()
    thr = np.asarray(THRESHOLDS_S)
    bands = [np.zeros((cal.height_px, cal.width_px), bool) for _ in thr]
    for b in bands:
        b[40:90] = True
    return cal, thr, bands


def _approach(
    oncoming: bool, standing: bool, stands_from: int = 99, across_from: int = 99, view: str = "fovea"
) -> list[tuple[bool, bool]]:
    """Per job, whether ``view``'s regions count as predicted, and whether ``view`` is
    among the views holding oncoming traffic predicted into the path
    (``PathPrediction.oncoming_views``): a box inside every fence that comes nearer (down
    and wider) job by job, floating above the counted rows (``standing``: reaching their
    lowest row; from job ``stands_from`` on), right of the image centre (from job
    ``across_from`` on, across it), in a camera whose two views are alike."""
    cal, thr, bands = _judged_rows_40_to_89()
    h, w = cal.height_px, cal.width_px
    tracker = TrackerConfig(oncoming=oncoming)
    paths = PathPrediction(GeofenceConfig(thresholds_s=THRESHOLDS_S, tracker=tracker), {"wide": cal, "fovea": cal})
    out = []
    for k in range(8):
        t = 0.1 * k
        paths.start_job(t, SPEED_MPS, 0.0)
        maps = np.zeros((len(thr), h, w), np.float32)
        half = 6 + k  # [px] it grows as it nears, centred right of the image centre
        bottom = 89 if standing or k >= stands_from else 60 + 2 * k
        left = int(cal.cx_px) + (2 if k < across_from else -4)
        maps[:, 45 : bottom + 1, left : left + 2 * half] = 1.0
        for v in ("wide", "fovea"):
            paths.observe(v, maps, thr, bands, SPEED_MPS, t)
        predicted = paths.predicted(view, (h, w), t, SPEED_MPS, 0.0).any()
        out.append((bool(predicted), view in paths.oncoming_views))
    return out


def _fovea_predictions(oncoming: bool, standing: bool, stands_from: int = 99, across_from: int = 99) -> list[bool]:
    """Per job, whether the fovea's regions count as predicted (``_approach``)."""
    return [p for p, _ in _approach(oncoming, standing, stands_from, across_from)]


def test_the_fovea_predicts_its_floating_tracks_only():
    two_views = {"wide": _cal(), "fovea": _cal()}
    assert PathPrediction(GeofenceConfig(thresholds_s=THRESHOLDS_S), two_views).floating_only == ("fovea",)
    assert not any(_fovea_predictions(oncoming=False, standing=False))
    assert not any(_fovea_predictions(oncoming=True, standing=True))
    assert _fovea_predictions(oncoming=True, standing=False) == [False] * 2 + [True] * 6
    # a fovea track that floated stays floating when its region comes to reach the rows
    assert _fovea_predictions(oncoming=True, standing=False, stands_from=5) == [False] * 2 + [True] * 6


def test_a_predicted_oncoming_car_across_the_centre_stays_predicted(monkeypatch):
    # from job 4 on its region spans the image centre and its prediction is made to fail:
    # it is ahead now, and stays predicted while it lies across the centre
    in_path = BlobTracker.in_path
    monkeypatch.setattr(BlobTracker, "in_path", lambda self, tr, t_s, *a: t_s < 0.35 and in_path(self, tr, t_s, *a))
    assert _fovea_predictions(oncoming=True, standing=False, across_from=4) == [False] * 2 + [True] * 6
    # beside the centre it is held for hold_jobs (2) more jobs only
    assert _fovea_predictions(oncoming=True, standing=False) == [False] * 2 + [True] * 4 + [False] * 2


def test_the_views_holding_predicted_oncoming_traffic_are_named_per_job(monkeypatch):
    assert _approach(oncoming=True, standing=False) == [(False, False)] * 2 + [(True, True)] * 6
    # the wide view names it too
    assert _approach(oncoming=True, standing=False, view="wide") == [(False, False)] * 2 + [(True, True)] * 6
    # the same region predicted in the wide view as other than oncoming traffic is not named
    with monkeypatch.context() as m:
        m.setattr(BlobTracker, "oncoming", lambda self, tr: False)
        assert _approach(oncoming=True, standing=False, view="wide") == [(False, False)] * 2 + [(True, False)] * 6
    # a prediction that fails from job 4 on is held for hold_jobs (2) jobs, then dropped
    in_path = BlobTracker.in_path
    monkeypatch.setattr(BlobTracker, "in_path", lambda self, tr, t_s, *a: t_s < 0.35 and in_path(self, tr, t_s, *a))
    assert [o for _, o in _approach(oncoming=True, standing=False)] == [False] * 2 + [True] * 4 + [False] * 2


def _brake_with_oncoming(monkeypatch, views: set[str], tau_s: float | None = None, **cfg) -> tuple[float, str]:
    """(deceleration [m/s^2], stage) at the second job, on a wide view alone at 30 km/h, for
    a car 12 m ahead in the corridor (TTC ``tau_s``, by default 1.44 s: inside the 1.8 s
    fence, the partial stage, where a static obstacle asks 2.6 m/s^2: partial braking),
    with ``views`` named as holding oncoming traffic predicted into the path."""
    start_job = PathPrediction.start_job

    def with_oncoming(self, *a):
        start_job(self, *a)
        self.oncoming_views = set(views)

    monkeypatch.setattr(PathPrediction, "start_job", with_oncoming)
    d, speed = 12.0, 30 / 3.6
    cmds = gc.run(gc.add_box(gc.road(speed), d, 0.0, tau_s or d / speed), speed=speed, cfg=cfg)
    return cmds[1].decel_mps2, cmds[1].telemetry["stage"]


def test_oncoming_traffic_in_the_path_brakes_fully_at_the_partial_stage(monkeypatch):
    assert _brake_with_oncoming(monkeypatch, set()) == (4.0, "partial")
    assert _brake_with_oncoming(monkeypatch, {"wide"}) == (9.0, "full-oncoming")
    assert _brake_with_oncoming(monkeypatch, {"wide"}, oncoming_full=False) == (4.0, "partial")
    # only where the view whose fence fired holds it
    assert _brake_with_oncoming(monkeypatch, {"fovea"}) == (4.0, "partial")
    # and only at a braking stage: in the 2.8 s fence alone it warns
    assert _brake_with_oncoming(monkeypatch, {"wide"}, tau_s=2.5) == (0.0, "warn")


def test_fenced_blobs_sizes_a_region_where_its_ground_lies():
    # a 5 x 10 px region in both fences, the ground under it free 60 m away: too small for
    # the 100 px asked at the largest fence's static depth, as big as a face asks at 60 m
    h, w = 96, 288
    thr = np.array([0.8, 2.8])
    maps = np.zeros((2, h, w), np.float32)
    maps[:, 40:50, 100:105] = 1.0
    inside = maps[1] > 0.5
    ground = np.full(h, 60.0)
    far = lambda z: max(8.0, 180000.0 / z**2)  # noqa: E731  (50 px at 60 m)
    assert not fenced_blobs(inside, inside, maps, thr, 0.5, 100.0, ground)
    (blob,) = fenced_blobs(inside, inside, maps, thr, 0.5, 100.0, ground, need_far_px=far)
    assert blob.contact_depth_m == 60.0
    assert not fenced_blobs(inside, inside, maps, thr, 0.5, 100.0, np.full(h, 50.0), need_far_px=far)
    # a region whose ground lies nearer than the largest fence's static depth needs need_px
    maps[:, 40:50, 100:115] = 1.0  # 150 px, where a face 20 m away asks 450
    (blob,) = fenced_blobs(maps[1] > 0.5, maps[1] > 0.5, maps, thr, 0.5, 100.0, np.full(h, 20.0), need_far_px=far)
    # where the fence reaches the image's bottom under it, its ground is not known
    maps[:] = 0.0
    maps[:, 40:50, 100:105] = 1.0
    maps[0, 40:, 100:105] = 1.0
    assert not fenced_blobs(inside, inside, maps, thr, 0.5, 100.0, ground, need_far_px=far)


def test_path_prediction_sizes_by_the_ground_only_with_the_oncoming_rules():
    # 9 px floating on the ground 52 m ahead: short of the 9.9 px a face asks at the 2.8 s
    # fence's static depth (31 m), enough for the 8 px asked where it stands
    cal, thr, bands = _judged_rows_40_to_89()
    h, w = cal.height_px, cal.width_px
    maps = np.zeros((len(thr), h, w), np.float32)
    maps[:, 49:52, 150:153] = 1.0
    seen = []
    for oncoming in (True, False):
        cfg = GeofenceConfig(thresholds_s=THRESHOLDS_S, tracker=TrackerConfig(oncoming=oncoming))
        paths = PathPrediction(cfg, {"wide": cal, "fovea": cal})
        paths.start_job(0.0, SPEED_MPS, 0.0)
        paths.observe("wide", maps, thr, bands, SPEED_MPS, 0.0)
        seen.append(len(paths._seen["wide"]))
    assert seen == [1, 0]
