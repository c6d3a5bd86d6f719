"""The registered Gymnasium environment: API conformance and seeded determinism."""

import gymnasium as gym
import numpy as np
from gymnasium.utils.env_checker import check_env

import sim  # noqa: F401  (registers bittc/Scenario-v0)


def test_check_env():
    env = gym.make("bittc/Scenario-v0", scenario="CCRs-30")
    check_env(env.unwrapped, skip_render_check=True)
    env.close()


def test_same_seed_same_rollout_and_truth_stays_in_info():
    def rollout(seed):
        env = gym.make("bittc/Scenario-v0", scenario="CCRs-40")
        obs, info = env.reset(seed=seed)
        images, rewards = [obs["image"]], []
        for k in range(80):
            obs, r, term, trunc, info = env.step(np.array([9.0 if k > 25 else 0.0], np.float32))
            images.append(obs["image"])
            rewards.append(r)
            if term or trunc:
                break
        env.close()
        assert set(obs) == {"image", "ego_speed_mps"}
        assert info["gt"]["tau_s"].shape == obs["image"].shape[:2] and info["critical"]["ttc_s"] > 0
        return images, rewards, info["end_reason"]

    a, b = rollout(5), rollout(5)
    assert a[2] == b[2] == "standstill" and a[1] == b[1]
    assert all(np.array_equal(x, y) for x, y in zip(a[0], b[0]))


def test_texture_styles_change_only_what_they_name():
    """The same seed with detailed vehicles: the same static world, other vehicle pixels;
    with the smooth ground: other ground pixels, the same vehicle pixels."""
    from sim.env import ScenarioEnv
    from sim.textures import TextureStyle

    def first_frame(style):
        env = ScenarioEnv("CCRs-10", textures=style)  # the target 14 m ahead
        obs, info = env.reset(seed=3)
        obs, _, _, _, info = env.step(np.zeros(1, np.float32))
        env.close()
        return obs["image"].astype(int), info["gt"]["instance"]

    detailed, inst = first_frame(TextureStyle(vehicles="detailed"))
    plain, inst_plain = first_frame(TextureStyle())  # plain vehicles by default
    assert np.array_equal(inst, inst_plain)
    vehicle = inst > 0
    assert vehicle.sum() > 50
    assert np.array_equal(detailed[~vehicle], plain[~vehicle])
    assert np.abs(detailed[vehicle] - plain[vehicle]).mean() > 3
    smooth, _ = first_frame(TextureStyle(ground="smooth"))
    assert np.array_equal(smooth[vehicle], plain[vehicle])
    assert not np.array_equal(smooth[inst == 0], plain[inst == 0])
