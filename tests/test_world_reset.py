"""A World rebuilt in place renders exactly what a new World with the same arguments
renders, whatever it held before, also across the periodic reconnect."""

import numpy as np
import pytest

import sim.world as world_mod
from sim.camera import CameraConfig, cam_T_ego
from sim.scenery import RoadConfig
from sim.textures import TextureBank
from sim.vehicles import sample_spec
from sim.world import World


def _scene(world: World) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(5)
    for k, kind in enumerate(("car", "truck")):
        inst = world.add_vehicle(sample_spec(rng, kind))
        world.set_vehicle_pose(inst, 12.0 + 8 * k, 3.5 * k, 0.3)
    r = world.render(cam_T_ego(world.camera))
    return r.rgb, r.depth_m, r.instance


@pytest.mark.parametrize("scenes_per_client", [256, 1])
def test_reset_renders_like_a_new_world(tmp_path, monkeypatch, scenes_per_client):
    monkeypatch.setattr(world_mod, "SCENES_PER_CLIENT", scenes_per_client)
    bank = TextureBank(0, tmp_path)
    cam = CameraConfig()
    road_a, road_b = RoadConfig(lanes_left=2, x_end_m=300), RoadConfig(lanes_right=0, x_end_m=250, barrier=False)
    fresh = World(cam, road_b, seed=11, bank=bank)
    reused = World(cam, road_a, seed=3, bank=bank)
    try:
        expected = _scene(fresh)
        _scene(reused)  # vehicles and scenery of another scene, then replaced
        reused.reset(cam, road_b, seed=11)
        got = _scene(reused)
        for e, g in zip(expected, got):
            assert np.array_equal(e, g)
        assert set(np.unique(got[2])) == {-1, 0, 1, 2}  # sky, static, both vehicles
    finally:
        fresh.close()
        reused.close()
