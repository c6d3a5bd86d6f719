"""The geofence controller on hand-made maps (``tests.geofence_maps``): no renderer, no
network. The fovea beside the wide view: test_geofence_fovea.py."""

import math

import numpy as np
import pytest

from bittc_core.errors import ConfigError
from controllers.base import Calibration, Observation
from controllers.evidence import fenced_road_edge, judged_pixels
from controllers.geofence import GeofenceConfig, GeofenceController, default_thresholds
from sim.camera import CameraConfig
from sim.vehicles import EGO_SIZE_M
from tests.geofence_maps import CAL, CAM, SPEED, THR, MapEstimator, add_box, quiet, road, run


def test_the_road_ahead_alone_is_ignored():
    assert quiet(run(road()))
    est = MapEstimator()
    est.tau = road()
    assert est.geofence(None, None, [2.4])[0].sum() > 1000  # the fences do cover the road


def _run_with(tau_map, **settings):
    est = MapEstimator()
    est.tau = tau_map
    ctrl = GeofenceController(est, GeofenceConfig(thresholds_s=THR, frame_stride=1, **settings))
    ctrl.reset(CAL)
    img = np.zeros((CAM.height_px, CAM.width_px, 3), np.uint8)
    return [ctrl.act(Observation(0.1 * k, SPEED, img, img, 0.1, CAL), None) for k in range(3)]


@pytest.mark.parametrize("early", [0.5, 0.6])
def test_a_minimum_height_ignores_a_road_fenced_past_its_boundary(early):
    """The road read as closing 1.7-2x faster than it does: its fence runs past the counted
    rows' boundary and leaves a strip a few rows tall along the lowest counted row, in the
    corridor. Without a minimum height in this view the 0.8 s fence fires on it; with
    ``min_height_m`` it has no height and is not an obstacle, while a car still fires."""
    assert not quiet(_run_with(road() * early, min_height_views=()))
    assert quiet(_run_with(road() * early, min_height_m=0.3, min_height_views=("wide",)))
    d = 20.0
    assert not quiet(_run_with(add_box(road() * early, d, 0.0, d / SPEED), min_height_views=("wide",)))


@pytest.mark.parametrize("early", [0.5, 0.6])
def test_the_road_s_own_fence_edge_bounds_the_counted_rows(early):
    """The road read as closing faster than it does, with a small bump of its fence edge in
    the corridor: without the bound (the default) the 0.8 s fence fires on the strip of
    road it fences past the counted rows' boundary; with it the counted rows end above
    the edge, and a car still fires."""
    bumped = road() * early
    edge = int(np.flatnonzero(bumped[:, 0] <= THR[0]).min())  # the 0.8 s fence's edge row
    cols = slice(CAM.width_px // 2 - 6, CAM.width_px // 2 + 6)
    bumped[edge - 2 : edge, cols] = 0.5 * THR[0]
    assert not quiet(_run_with(bumped, min_height_views=()))
    assert quiet(_run_with(bumped, road_edge_rows=1, min_height_views=()))
    d = 20.0
    assert not quiet(_run_with(add_box(bumped, d, 0.0, d / SPEED), road_edge_rows=1, min_height_views=()))


def test_the_fenced_road_edge_is_the_median_top_of_the_runs_from_the_bottom():
    inside = np.zeros((10, 20), dtype=bool)
    assert fenced_road_edge(inside) is None  # no column has a run from the bottom row
    inside[6:, :] = True  # the road fenced up to row 6
    inside[1:, 3:5] = True  # an obstacle in two columns, outvoted
    assert fenced_road_edge(inside) == 6
    assert fenced_road_edge(np.ones((10, 20), dtype=bool)) == 0
    few = np.zeros((10, 20), dtype=bool)
    few[5:, :1] = True  # one column in twenty: under the tenth
    assert fenced_road_edge(few) is None


def test_the_bound_drops_the_rows_up_to_n_above_the_edge():
    tau_ground = road()
    inside = tau_ground <= 2 * THR[0]  # the road fenced to twice its static depth
    edge = fenced_road_edge(inside)
    fence = inside.astype(np.float32)  # the map, p(0 < tau <= 0.8 s)
    for n in (0, 3):
        cfg = GeofenceConfig(road_edge_rows=n, road_edge_cap=math.inf)
        band = judged_pixels(tau_ground, fence, THR[0], cfg)
        assert int(np.flatnonzero(band.any(axis=1)).max()) == edge - n - 1
    off = judged_pixels(tau_ground, fence, THR[0], GeofenceConfig())
    assert int(np.flatnonzero(off.any(axis=1)).max()) > edge  # the default counts the fenced road


def test_the_road_edge_settings_are_checked_and_reach_the_controllers():
    import controllers

    assert GeofenceConfig().road_edge_rows == -1  # off by default
    for name in ("geofence-exact", "flow"):
        assert controllers.make(name, road_edge_rows=3).cfg.road_edge_rows == 3
        assert controllers.make(name, turn_across=False).cfg.tracker.turn_across is False
        assert controllers.make(name).cfg.tracker.turn_across is True
        assert controllers.make(name, oncoming=False).cfg.tracker.oncoming is False
        assert controllers.make(name, oncoming=False).cfg.tracker.turn_across is True
        assert controllers.make(name).cfg.tracker.oncoming is True
    for bad in (-2, True, 1.5):
        with pytest.raises(ConfigError, match="road_edge_rows"):
            GeofenceConfig(road_edge_rows=bad)
    GeofenceConfig(ground_margin=2.5)  # the cap is checked only with the bound on
    with pytest.raises(ConfigError, match="road_edge_cap"):
        GeofenceConfig(road_edge_rows=1, road_edge_cap=1.0)


def test_a_car_in_the_adjacent_lane_is_ignored():
    d = 20.0  # a static car 20 m ahead, one lane to the left: tau = d / v
    assert quiet(run(add_box(road(), d, 3.5, d / SPEED)))
    assert quiet(run(add_box(road(), d, -3.5, d / SPEED)))


def test_an_oncoming_car_in_the_next_lane_is_ignored():
    d = 40.0  # closing at twice the ego's speed
    assert quiet(run(add_box(road(), d, 3.5, d / (2 * SPEED))))


def test_a_car_in_the_corridor_fires_after_persistence_and_latches():
    d = 20.0
    tau_s = d / SPEED  # 1.44 s: inside the 1.8 s fence
    cmds = run(add_box(road(), d, 0.0, tau_s), jobs=3)
    assert quiet(cmds[:1])  # one job is not enough (persistence 2)
    assert cmds[1].warning and cmds[1].decel_mps2 > 0  # the 1.8 s fence is nearest to partial: 1.6 + 1.5/13.9 s
    assert cmds[1].telemetry["fence_fired_s"] == 1.8
    assert cmds[1].view.counted.any()


def test_a_half_overlapping_car_fires():
    d = 20.0
    assert not quiet(run(add_box(road(), d, 0.9, d / SPEED)))


def test_one_fence_warns_and_brakes():
    d = 20.0
    cmds = run(add_box(road(), d, 0.0, d / SPEED), thresholds=(1.5,))
    assert cmds[-1].warning and cmds[-1].decel_mps2 == 9.0


def test_standing_ego_neither_warns_nor_brakes():
    tau = np.full((CAM.height_px, CAM.width_px), np.inf)
    assert quiet(run(add_box(tau, 10.0, 0.0, 1.0), speed=0.0))


def test_default_thresholds_rule():
    assert default_thresholds(1) == (1.4967,)
    t = default_thresholds(4)
    assert t[0] == 0.8 and t[-1] == 2.8 and np.allclose(np.diff(np.log(t)), math.log(3.5) / 3, atol=1e-4)


@pytest.mark.parametrize("bad", [(), (0.0,), (-1.0,), (math.nan,), (1.0, 1.0), (math.inf,)])
def test_bad_thresholds_are_refused(bad):
    with pytest.raises(ConfigError, match="threshold"):
        GeofenceConfig(thresholds_s=bad)


def test_a_frame_interval_outside_the_trained_range_is_refused():
    ctrl = GeofenceController(MapEstimator(), GeofenceConfig(thresholds_s=(0.3,), frame_stride=1))
    fast = Calibration.from_camera(CameraConfig(fps_hz=5.0), EGO_SIZE_M)  # 0.3 s at 0.2 s -> 0.15 s at 0.1 s
    with pytest.raises(ConfigError, match="frame interval 0.2 s"):
        ctrl.reset(fast)


def test_a_turned_pair_is_derotated_and_counts_only_the_tracker_s_regions():
    """A pair that turned past ``max_rotation_px``: the estimator gets the earlier frame
    warped by the turn, the job reports it (a profile charges its extraction anew), and a
    car in the bent corridor at the fences' static depth no longer counts there."""
    from controllers.tracker import TrackerConfig

    class Recording(MapEstimator):
        def geofence(self, prev, latest, thresholds_s):
            self.prev = prev
            return super().geofence(prev, latest, thresholds_s)

    def jobs(yaw_radps, **settings):
        est = Recording()
        est.tau = add_box(road(), 20.0, 0.0, 20.0 / SPEED)
        tracker = TrackerConfig(predict_unchecked=True)  # a wide view that tracks: no fovea here
        ctrl = GeofenceController(est, GeofenceConfig(thresholds_s=THR, frame_stride=1, tracker=tracker, **settings))
        ctrl.reset(CAL)
        prev = np.random.default_rng(0).integers(0, 255, (CAM.height_px, CAM.width_px, 3), dtype=np.uint8)
        latest = prev.copy()
        cmds = []
        for k in range(3):
            obs = Observation(
                0.1 * k, SPEED, latest, prev, 0.1, CAL, ego_yaw_rate_radps=yaw_radps, pair_yaw_rad=0.1 * yaw_radps
            )
            cmds.append(ctrl.act(obs, None))
        return cmds, est.prev is prev

    straight, same = jobs(0.0)
    assert not quiet(straight) and same and straight[-1].telemetry["derotated"] == ""
    turned, same = jobs(1.0)  # 0.1 rad in the pair: 18 px in the wide view
    assert quiet(turned) and not same and turned[-1].telemetry["derotated"] == "wide"
    _, same = jobs(1.0, derotate=False)
    assert same
