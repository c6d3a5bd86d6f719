"""The fovea: a crop of a zoom-times larger sensor, rendered through an off-axis frustum,
with exact ground truth from the same code as the wide view."""

import math

import numpy as np
import pytest

from controllers.base import Calibration
from controllers.road import ground_depth_per_row
from sim.camera import CameraConfig, cam_T_ego
from sim.cli import main
from sim.scenery import RoadConfig
from sim.vehicles import EGO_SIZE_M
from sim.world import World


@pytest.mark.parametrize("zoom", [2.0, 4.0, 3.3])
def test_a_points_fovea_pixel_is_the_crop_mapping_of_its_wide_pixel(zoom):
    cam = CameraConfig(fovea_zoom=zoom, pitch_deg=3.0)
    rng = np.random.default_rng(0)
    p_ego = np.c_[rng.uniform(5, 150, 50), rng.uniform(-10, 10, 50), rng.uniform(-1, 4, 50), np.ones(50)]
    p_cam = (cam_T_ego(cam) @ p_ego.T).T[:, :3]
    uv_wide, uv_fovea = cam.wide().project(p_cam), cam.fovea().project(p_cam)
    np.testing.assert_allclose(cam.fovea_from_wide(uv_wide), uv_fovea, atol=1e-9)
    # the crop of a zoom-times larger sensor: pixel offsets from the principal point scale by the zoom
    wide, fov = cam.wide(), cam.fovea()
    np.testing.assert_allclose(uv_fovea[:, 0] - fov.cx_px, zoom * (uv_wide[:, 0] - wide.cx_px))
    assert fov.fx_px == pytest.approx(zoom * wide.fx_px) and (fov.height_px, fov.width_px) == (96, 144)


def test_the_horizon_point_ahead_lies_at_the_fovea_centre():
    cam = CameraConfig(fovea_zoom=4.0, pitch_deg=2.0)
    far_ahead = cam_T_ego(cam) @ np.array([1e6, 0.0, cam.mount_height_m, 1.0])
    u, v = cam.fovea().project(far_ahead[:3])[0]
    assert (u, v) == (pytest.approx(71.5), pytest.approx(47.5, abs=1e-3))  # 144 px wide
    # while the wide view has it above its centre, by fy tan(pitch)
    v_wide = cam.wide().project(far_ahead[:3])[0, 1]
    assert v_wide == pytest.approx(47.5 - cam.wide().fy_px * math.tan(math.radians(2.0)), abs=1e-3)


@pytest.mark.parametrize("bad", [0.5, 0.0, -2.0, math.nan, math.inf, 17.0, True, "4"])
def test_a_bad_zoom_is_refused_by_value(bad):
    with pytest.raises(ValueError, match="fovea zoom"):
        CameraConfig(fovea_zoom=bad)


@pytest.fixture(scope="module")
def world():
    # pitched down so that the fovea's principal point lies far off its centre (off-axis frustum)
    cam = CameraConfig(pitch_deg=4.0, mount_forward_m=0.0, mount_height_m=1.0, fovea_zoom=4.0)
    w = World(
        cam, RoadConfig(x_start_m=-100, x_end_m=-60, barrier=False, buildings=False, roadside_spacing_m=1e3), seed=0
    )
    yield w
    w.close()


@pytest.mark.parametrize("v_edge", [30.3, 30.7, 61.2, 61.8])
def test_a_horizontal_edge_lands_where_the_fovea_intrinsics_say(world, v_edge):
    """A wall's top edge at a known height: every fovea row below the projected edge is covered."""
    cam, fov = world.camera, world.camera.fovea()
    T = cam_T_ego(cam)
    Z = 40.0  # [m] the wall's distance along the ego's x axis
    # the ego-frame height whose projection in the fovea is row v_edge at column cx (bisection)
    lo, hi = -20.0, 20.0
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        v = fov.project((T @ np.array([Z, 0.0, mid, 1.0]))[:3])[0, 1]
        lo, hi = (mid, hi) if v > v_edge else (lo, mid)
    top = 0.5 * (lo + hi)
    uid = world.add_static_box((Z, 0.0, top - 25.0), (0.01, 50.0, 25.0), None)
    try:
        r = world.render(T, pinhole=fov)
        col = r.instance[:, int(round(fov.cx_px))]
        covered = np.where(col >= 0)[0]
        assert covered.min() == int(np.ceil(v_edge))  # pixel centres at integer rows
    finally:
        world.client.removeBody(uid)


def test_the_fovea_render_of_the_ground_matches_its_calibration():
    """Depth of the flat road per fovea row (centre column) against the closed form of controllers.road."""
    cam = CameraConfig(fovea_zoom=4.0)
    w = World(cam, RoadConfig(x_end_m=200, barrier=False, buildings=False, roadside_spacing_m=1e3), seed=0)
    try:
        cal = Calibration.from_camera(cam, EGO_SIZE_M).fovea
        r = w.render(cam_T_ego(cam), pinhole=cam.fovea())
        u = int(round(cal.cx_px))
        expected = ground_depth_per_row(cal)
        rows = [v for v in range(cal.height_px) if np.isfinite(expected[v]) and expected[v] < 150]
        assert len(rows) > 20
        # depth along the optical axis of the road point seen on that row
        np.testing.assert_allclose([r.depth_m[v, u] for v in rows], [expected[v] for v in rows], rtol=5e-3)
    finally:
        w.close()


def test_scenario_ground_truth_in_both_views_from_the_same_code():
    from scenarios import resolve
    from sim.episode import ScenarioSim

    cam = CameraConfig(fovea_zoom=4.0)
    sim = ScenarioSim(resolve("CCRs-50")[0], cam, seed=0, render=True)
    try:
        sim.reset()
        prev = sim.capture()
        for _ in range(sim.n_sub):
            sim.substep(0.0)
        latest = sim.capture()
        wide, fovea = sim.ground_truth(prev, latest, "wide"), sim.ground_truth(prev, latest, "fovea")
        target = 1  # the GVT
        pw, pf = wide.instance == target, fovea.instance == target
        assert pw.sum() >= 4 and pf.sum() > 8 * pw.sum()  # magnified ~zoom^2 in area
        # the same 3D points: the same exact TTC and motion in depth in both views
        assert np.median(fovea.tau_s[pf]) == pytest.approx(np.median(wide.tau_s[pw]), rel=0.02)
        assert np.median(fovea.eta[pf]) == pytest.approx(np.median(wide.eta[pw]), rel=1e-3)
        assert latest.image.shape == (96, 288, 3) and latest.fovea.rgb.shape == (96, 144, 3)  # half as wide
    finally:
        sim.close()


@pytest.mark.parametrize("bad", ["0.5", "nan", "inf", "17", "big"])
def test_cli_refuses_a_bad_fovea_and_writes_nothing(tmp_path, capsys, bad):
    out = tmp_path / "run"
    assert main(["run", "CCRs-50", "--controller", "oracle", "--fovea", bad, "--out", str(out)]) == 2
    assert "--fovea" in capsys.readouterr().err and not out.exists()
