"""Gymnasium environment: one scenario case, camera observations, brake actions.

Registered as ``bittc/Scenario-v0``::

    env = gymnasium.make("bittc/Scenario-v0", scenario="CCRs-50")

Observation Space (Dict):
    ============== ======================= =============================================
    key            space                   meaning
    ============== ======================= =============================================
    image          Box(0, 255, (H, W, 3))  latest ego-camera frame, uint8 RGB
    ego_speed_mps  Box(0, 60, (1,))        the ego's own speed [m/s]
    ============== ======================= =============================================

Action Space: Box(0, 9, (1,)) — requested deceleration [m/s^2], applied through the
actuator model (0.1 s delay, 30 m/s^3 jerk limit) for one frame interval.

Reward: -1 on the step of a collision, minus 0.01 per (m/s^2 * s) of braking (a mild
comfort cost); 0 otherwise.

Episode End:
    terminated — 1 s after a collision, ego standstill with nothing closing in, or the
    threat resolved after braking (see :meth:`sim.episode.ScenarioSim.done`).
    truncated — the scenario's ``duration_s`` is reached.

Ground truth (per-pixel eta/tau/flow/depth maps, per-actor gaps and TTCs, collision)
travels in ``info``, never in the observation. The scenery seed is drawn from
``self.np_random``, so ``reset(seed=s)`` fixes every pixel. ``textures`` (a
``sim.textures.TextureStyle``) picks the ground and vehicle texture styles (detailed
ground and plain vehicles by default).
"""

from __future__ import annotations

from dataclasses import asdict

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from sim.camera import CameraConfig
from sim.episode import ScenarioSim
from sim.textures import TextureStyle

MAX_DECEL_MPS2 = 9.0  # [m/s^2]
MAX_SPEED_MPS = 60.0  # [m/s]


class ScenarioEnv(gym.Env):
    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}

    def __init__(self, scenario: str = "CCRs-50", camera: CameraConfig | None = None, render_mode: str | None = None,
                 textures: TextureStyle | None = None):  # fmt: skip
        import scenarios

        cases = scenarios.resolve(scenario)
        if len(cases) != 1:
            raise ValueError(f"scenario {scenario!r} expands to {len(cases)} cases; name one case (e.g. {cases[0].name})")
        self.case = cases[0]
        self.camera = camera or CameraConfig()
        if textures is not None and not isinstance(textures, TextureStyle):
            raise ValueError(f"textures={textures!r}: expected a sim.textures.TextureStyle")
        self.textures = textures or TextureStyle()
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode {render_mode!r} is not supported")
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_fps": self.camera.fps_hz}
        h, w = self.camera.height_px, self.camera.width_px
        self.observation_space = spaces.Dict({
            "image": spaces.Box(0, 255, (h, w, 3), np.uint8),
            "ego_speed_mps": spaces.Box(0.0, MAX_SPEED_MPS, (1,), np.float32),
        })  # fmt: skip
        self.action_space = spaces.Box(0.0, MAX_DECEL_MPS2, (1,), np.float32)
        self._sim: ScenarioSim | None = None
        self._prev = self._frame = None

    def _obs(self) -> dict:
        return {"image": self._frame.image, "ego_speed_mps": np.array([min(self._sim.ego.speed, MAX_SPEED_MPS)], np.float32)}

    def _info(self, truth) -> dict:
        """Ground truth as plain dicts and arrays: per-actor truth, the critical actor,
        the collision, and (from the second frame on) the per-pixel maps."""
        info = {
            "t_s": truth.t_s,
            "actors": [asdict(a) for a in truth.actors],
            "critical": asdict(truth.critical) if truth.critical is not None else None,
            "collision": asdict(truth.collision) if truth.collision is not None else None,
        }
        if self._prev is not None:
            info["gt"] = asdict(self._sim.ground_truth(self._prev, self._frame))
        return info

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        self.close()
        world_seed = int(self.np_random.integers(2**31 - 1))
        self._sim = ScenarioSim(self.case, self.camera, world_seed, render=True, textures=self.textures)
        truth = self._sim.reset()
        self._prev, self._frame = None, self._sim.capture()
        return self._obs(), self._info(truth)

    def step(self, action):
        if self._sim is None:
            raise RuntimeError("call reset() before step()")
        decel = float(np.clip(np.asarray(action, np.float32).reshape(-1)[0], 0.0, MAX_DECEL_MPS2))
        had_collision = self._sim.collision is not None
        for _ in range(self._sim.n_sub):
            self._sim.substep(decel)
        self._prev, self._frame = self._frame, self._sim.capture()
        truth = self._sim.truth()
        reason = self._sim.done(truth)
        reward = -0.01 * decel * self.camera.dt_s
        if self._sim.collision is not None and not had_collision:
            reward -= 1.0
        info = self._info(truth)
        info["end_reason"] = reason
        return self._obs(), float(reward), reason in ("collision", "standstill", "resolved"), reason == "duration", info

    def render(self):
        if self.render_mode == "rgb_array" and self._frame is not None:
            return self._frame.image
        return None

    def close(self):
        if self._sim is not None:
            self._sim.close()
            self._sim = None
