"""The registered Gymnasium environment: API conformance, seeded determinism, latency
charged as in `bittc run`, the geofence wrapper and vector envs."""

import math

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import sim  # noqa: F401  (registers bittc/Scenario-v0)
from sim.env import GeofenceObservation, ScenarioEnv


def test_check_env():
    env = gym.make("bittc/Scenario-v0", scenario="CCRs-30")
    check_env(env.unwrapped, skip_render_check=True)
    env.close()


def test_check_env_with_geofences():
    env = GeofenceObservation(ScenarioEnv("CCRs-30", latency="profile:this-cpu"), estimator="flow", num_alphas=2)
    check_env(env, skip_render_check=True)
    obs, _ = env.reset(seed=1)
    assert obs["geofence"].shape == (2, 96, 288) and np.allclose(obs["thresholds_s"], [0.8, 2.8])
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
        assert set(obs) == {"image", "image_prev", "ego_speed_mps", "ego_yaw_rate_radps", "pair_yaw_rad", "calibration"}
        assert info["gt"]["tau_s"].shape == obs["image"].shape[:2] and info["critical"]["ttc_s"] > 0
        return images, rewards, info["end_reason"]

    a, b, c = rollout(5), rollout(5), rollout(6)
    assert a[2] == b[2] == "standstill" and a[1] == b[1]
    assert all(np.array_equal(x, y) for x, y in zip(a[0], b[0]))
    assert not all(np.array_equal(x, y) for x, y in zip(a[0], c[0]))  # another seed: another rollout


def test_latency_skips_frames_as_the_runner_does():
    """150 ms of latency: a step spans 1.5 frames on average, as in the streaming schedule."""
    env = ScenarioEnv("CCRs-30", latency="fixed:150")
    _, info = env.reset(seed=0)
    times = [info["t_s"]]
    for _ in range(4):
        _, _, _, _, info = env.step(np.zeros(1, np.float32))
        times.append(info["t_s"])
    env.close()
    assert np.allclose(times, [0.1, 0.2, 0.4, 0.5, 0.7])


def test_reset_option_picks_the_scenario():
    env = ScenarioEnv("CCRs-30")
    env.reset(seed=0, options={"scenario": "CCRm-50"})
    assert env.case.name == "CCRm-50"
    with pytest.raises(ValueError, match="expands to"):
        env.reset(options={"scenario": "CCRs"})
    env.close()


@pytest.mark.parametrize("action", [[math.nan], [-0.5], [9.5], [1.0, 2.0]])
def test_bad_actions_are_refused_by_value(action):
    env = ScenarioEnv("CCRs-30")
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action"):
        env.step(np.array(action, np.float32))
    env.close()


def test_vector_env_sync():
    envs = gym.make_vec(
        "bittc/Scenario-v0",
        num_envs=2,
        vectorization_mode="sync",
        scenario="CCRs-20",
        wrappers=[lambda e: GeofenceObservation(e, estimator="flow", thresholds_s=[1.0, 2.0])],
    )
    obs, _ = envs.reset(seed=3)
    assert obs["geofence"].shape == (2, 2, 96, 288)
    obs, r, term, trunc, _ = envs.step(np.zeros((2, 1), np.float32))
    assert r.shape == (2,) and obs["image"].shape == (2, 96, 288, 3)
    envs.close()


def test_texture_styles_change_only_what_they_name():
    """The same seed with detailed vehicles: the same static world, other vehicle pixels;
    with the smooth ground: other ground pixels, the same vehicle pixels."""
    from sim.textures import TextureStyle

    def first_frame(style):
        env = ScenarioEnv("CCRs-10", textures=style)  # the target 14 m ahead
        obs, info = env.reset(seed=3)
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


def test_the_fovea_is_observed_and_its_truth_stays_in_info():
    from sim.camera import CameraConfig

    base = ScenarioEnv("CCRs-30", camera=CameraConfig(fovea_zoom=4.0), latency="profile:this-cpu")
    env = GeofenceObservation(base, estimator="flow", num_alphas=2)
    check_env(env, skip_render_check=True)
    obs, info = env.reset(seed=1)
    assert {"fovea_image", "fovea_image_prev", "fovea_calibration", "fovea_geofence"} <= set(obs)
    assert obs["fovea_geofence"].shape == (2, 96, 144) and obs["fovea_image"].shape == (96, 144, 3)  # half as wide
    assert obs["fovea_calibration"][0] == pytest.approx(4 * obs["calibration"][0])
    assert "fovea_gt" in info and "fovea_gt" not in obs
    env.close()


def test_measured_mode_charges_the_agents_own_time():
    """An agent that answers at once acts on the next frame; one that thinks 250 ms first
    acts only after it, so the frame captured meanwhile (0.2 s) is skipped."""
    import time

    def next_t(think_s: float) -> float:
        env = ScenarioEnv("CCRs-30", latency="measured")
        _, info = env.reset(seed=0)
        assert info["t_s"] == pytest.approx(0.1)
        time.sleep(think_s)
        _, _, _, _, info = env.step(np.zeros(1, np.float32))
        env.close()
        return info["t_s"]

    assert next_t(0.0) == pytest.approx(0.2)
    assert next_t(0.25) >= 0.3 - 1e-9


def test_a_turning_ego_observes_its_yaw_rate_and_the_pair_s_rotation():
    env = ScenarioEnv("CCFtap-20-30")
    obs, _ = env.reset(seed=0)
    seen = []
    for _ in range(45):
        obs, _, term, trunc, _ = env.step(np.array([0.0], np.float32))
        assert env.observation_space.contains(obs)
        seen.append((float(obs["ego_yaw_rate_radps"][0]), float(obs["pair_yaw_rad"][0])))
        if term or trunc:
            break
    env.close()
    assert seen[0] == (0.0, 0.0)  # straight on at first
    assert max(w for w, _ in seen) > 0.2 and max(p for _, p in seen) > 0.01  # then a left turn
