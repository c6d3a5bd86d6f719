"""The intrinsics are exact: geometry rendered by TinyRenderer lands where K predicts."""

import numpy as np
import pytest

from sim.camera import CameraConfig, cam_T_ego
from sim.scenery import RoadConfig
from sim.vehicles import VehicleSpec
from sim.world import World


@pytest.fixture(scope="module")
def world():
    cam = CameraConfig(pitch_deg=0.0, mount_forward_m=0.0, mount_height_m=1.0)
    w = World(
        cam, RoadConfig(x_start_m=-100, x_end_m=-60, barrier=False, buildings=False, roadside_spacing_m=1e3), seed=0
    )
    yield w
    w.close()


@pytest.mark.parametrize("u_edge", [143.3, 143.7, 150.2, 150.8])
def test_vertical_edge_lands_where_intrinsics_say(world, u_edge):
    cam = world.camera
    fx, fy, cx, cy = cam.intrinsics()
    Z = 10.0
    y_edge = -(u_edge - cx) / fx * Z  # camera x = -ego y
    uid = world.add_static_box((Z, y_edge + 50.0, 1.0), (0.01, 50.0, 50.0), None)
    try:
        r = world.render(cam_T_ego(cam))
        covered = np.where(r.instance[cam.height_px // 2] >= 0)[0]
        # pixel centres at integer u: every column u < u_edge is covered, none above
        assert covered.max() == int(np.floor(u_edge))
        assert r.depth_m[cam.height_px // 2, 0] == pytest.approx(Z - 0.01, rel=1e-4)
    finally:
        world.client.removeBody(uid)


def test_two_worlds_in_one_process_are_independent():
    cam = CameraConfig()
    road = RoadConfig(x_end_m=100)
    a, b = World(cam, road, seed=1), World(cam, road, seed=1)
    try:
        ra, rb = a.render(cam_T_ego(cam)), b.render(cam_T_ego(cam))
        assert np.array_equal(ra.rgb, rb.rgb) and np.array_equal(ra.depth_m, rb.depth_m)
        inst = a.add_vehicle(VehicleSpec("car", 4.5, 1.8, 1.5))  # a body in one world only
        a.set_vehicle_pose(inst, 12.0, 0.0, 0.0)
        ra2, rb1 = a.render(cam_T_ego(cam)), b.render(cam_T_ego(cam))
        assert (ra2.instance == inst).sum() > 100 and not np.array_equal(ra2.rgb, ra.rgb)
        assert np.array_equal(rb1.rgb, rb.rgb) and not (rb1.instance > 0).any()
        a.close()
        rb2 = b.render(cam_T_ego(cam))
        assert np.array_equal(rb.rgb, rb2.rgb)
    finally:
        a.close()
        b.close()


@pytest.mark.parametrize("supersample", [1, 2])
def test_render_without_rgb_gives_no_image_and_the_same_maps(supersample):
    cam = CameraConfig(height_px=24, width_px=72, supersample=supersample)
    w = World(cam, RoadConfig(x_end_m=100, buildings=False), seed=0)
    try:
        full, maps_only = w.render(cam_T_ego(cam)), w.render(cam_T_ego(cam), with_rgb=False)
        assert full.rgb is not None and maps_only.rgb is None
        assert np.array_equal(full.depth_m, maps_only.depth_m) and np.array_equal(full.instance, maps_only.instance)
    finally:
        w.close()
