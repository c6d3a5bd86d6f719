"""The tracker's regions in the geofence controller, on hand-made maps (no renderer, no
network): which fenced regions it follows, and when the fovea refutes a prediction."""

import math

import numpy as np
import pytest

from controllers.base import Observation
from controllers.evidence import counted_pixels, ground_ttc_map, inner_edge_slant
from controllers.geofence import GeofenceConfig, GeofenceController
from controllers.path_prediction import PathPrediction
from controllers.road import ground_ttc_per_row
from controllers.tracker import TrackerConfig
from sim.camera import cam_T_ego
from tests.geofence_maps import (
    CAL,
    CAM,
    FOVEA_CAL,
    FOVEA_CAM,
    SPEED,
    THR,
    MapEstimator,
    ViewMapEstimator,
    add_box,
    road,
)

D0_M = 30.0  # [m] the target's distance at the first job


def _cfg(**tracker):
    """The tracker's settings; these tests follow its mechanics on a camera without a fovea
    too (``predict_unchecked``) unless told otherwise."""
    tracker = {"predict_unchecked": True} | tracker
    return GeofenceConfig(thresholds_s=THR, frame_stride=1, tracker=TrackerConfig(**tracker))


def _acted(cmds):
    return any(c.decel_mps2 > 0 or c.warning for c in cmds)


def _crossing(cfg: GeofenceConfig, jobs: int = 16):
    """Commands for a child (1.15 m) crossing from the right at 1.5 m/s whose centre meets
    the ego's path when the ego arrives (2.2 s after the first job, at 50 km/h)."""
    est = MapEstimator()
    ctrl = GeofenceController(est, cfg)
    ctrl.reset(CAL)
    img = np.zeros((CAM.height_px, CAM.width_px, 3), np.uint8)
    out = []
    for k in range(jobs):
        d = D0_M - SPEED * 0.1 * k
        est.tau = add_box(road(), d, -1.5 * d / SPEED, d / SPEED, width_m=0.5, height_m=1.15)
        out.append(ctrl.act(Observation(0.1 * k, SPEED, img, img, 0.1, CAL), None))
    return out


def test_a_crossing_child_is_braked_for_before_it_enters_the_corridor():
    cmds = _crossing(_cfg())
    first = next(k for k, c in enumerate(cmds) if c.decel_mps2 > 0)
    assert first <= 8  # 1.4 s before the ego arrives, while the child is 2 m right of the path
    assert not _acted(_crossing(_cfg(enabled=False)))
    # by default a camera without the fovea that checks its bearings predicts nothing
    assert not _acted(_crossing(_cfg(predict_unchecked=False)))


def _fovea_face(dist_m, lateral_m, tau_s, width_m=1.8, height_m=1.5):
    """The fovea's road with a face ``dist_m`` ahead centred ``lateral_m`` to the left."""
    cal = FOVEA_CAL.fovea
    tau = np.repeat(ground_ttc_per_row(cal, SPEED)[:, None], cal.width_px, axis=1)
    pin, T = FOVEA_CAM.fovea(), cam_T_ego(FOVEA_CAM)
    x = FOVEA_CAM.mount_forward_m + dist_m
    corners = [(T @ [x, lateral_m + width_m / 2, 0.0, 1.0])[:3], (T @ [x, lateral_m - width_m / 2, height_m, 1.0])[:3]]
    (u_a, v_bot), (u_b, v_top) = pin.project(np.array(corners))
    u0, u1 = max(int(min(u_a, u_b)), 0), min(int(math.ceil(max(u_a, u_b))), cal.width_px)
    tau[max(int(v_top), 0) : int(math.ceil(v_bot)), u0:u1] = tau_s
    return tau


def _held_edge(cfg: GeofenceConfig, jobs: int = 14):
    """A face standing 2.6 m right of the path (its inner edge 1.7 m right), as the fovea
    sees it, while the wide view's fence holds its inner edge at the bearing of the first
    job, as if it were on a collision course."""
    est = ViewMapEstimator()
    ctrl = GeofenceController(est, cfg)
    ctrl.reset(FOVEA_CAL)
    wide = np.zeros((CAM.height_px, CAM.width_px, 3), np.uint8)
    fov = wide.copy()
    fov[0, 0, 0] = 1
    out = []
    for k in range(jobs):
        d = D0_M - SPEED * 0.1 * k
        est.tau = add_box(road(), d, -(1.7 * d / D0_M + 0.9), d / SPEED)  # the inner edge's bearing held
        est.tau_fovea = _fovea_face(d, -2.6, d / SPEED)
        out.append(ctrl.act(Observation(0.1 * k, SPEED, wide, wide, 0.1, FOVEA_CAL, fov, fov), None))
    return out


def test_the_fovea_refutes_a_held_edge_that_it_sees_moving_out():
    # at 1.7 / 30 rad the held edge would cross at 0.8 m/s: let that count as moving; and let
    # the fovea's track match the wide one's until the two bearings part by 6 wide px
    settings = dict(min_speed_mps=0.5, check_tol_px=6.0)
    assert _acted(_held_edge(_cfg(check_views=(), **settings)))
    assert not _acted(_held_edge(_cfg(**settings)))


def test_inner_edge_slant_tells_an_upright_edge_from_a_strip_of_ground():
    upright = np.zeros((40, 100), bool)
    upright[5:35, 20:30] = True
    assert inner_edge_slant(upright, left_of_centre=True) == pytest.approx(0.0, abs=1e-9)
    # a strip of verge left of the centre: its nearer (lower) rows lie further out
    ground = np.zeros((40, 100), bool)
    for r in range(10, 30):
        ground[r, 0 : 60 - 2 * (r - 10)] = True
    assert inner_edge_slant(ground, left_of_centre=True) == pytest.approx(2.0)
    assert inner_edge_slant(ground[:, ::-1], left_of_centre=False) == pytest.approx(2.0)


def test_a_view_that_turned_too_far_ages_its_tracks():
    """A job whose pair turned too far gives no regions; the view's tracks miss it, and
    end after ``max_missed`` such jobs instead of waiting out the turn."""
    cfg = _cfg()
    paths = PathPrediction(cfg, {"wide": CAL})
    thr = np.asarray(THR)
    tau = add_box(road(), 20.0, -3.0, 20.0 / SPEED)
    maps = np.stack([(tau > 0) & (tau <= t) for t in thr]).astype(np.float32)
    bands = [counted_pixels(ground_ttc_map(CAL, SPEED), t, cfg.ground_margin) for t in thr]
    paths.start_job(0.0, SPEED, 0.0)
    paths.observe("wide", maps, thr, bands, SPEED, 0.0)
    assert len(paths.trackers["wide"].tracks) == 1
    for k in range(1, cfg.tracker.max_missed + 2):
        paths.start_job(0.1 * k, SPEED, 0.0)
        paths.observe("wide", maps, thr, None, SPEED, 0.1 * k)
    assert paths.trackers["wide"].tracks == []
