"""Gymnasium environment: one scenario case, camera observations, brake actions.

Registered as ``bittc/Scenario-v0``::

    env = gymnasium.make("bittc/Scenario-v0", scenario="CCRs-50", latency="fixed:50")
    obs, info = env.reset(seed=0, options={"scenario": "CCRm-50"})  # any case, same camera

The run goes through the closed-loop core (``sim.loop.ClosedLoop``), exactly as in
``bittc run``: a step is one job of the streaming schedule (``sim.latency``). The agent
sees a frame pair; its action is the command decided on that pair and takes effect
L after the job starts, where L comes from ``latency`` (``fixed:MS``, ``profile:NAME``, or
``measured``). In ``measured`` mode L is the compute charged by a wrapper such as
``GeofenceObservation`` plus the agent's own time: the wall time from the moment
``reset`` or ``step`` returned the observation to the moment the next ``step`` receives
the action (for a policy under test its compute is latency too; an agent that does other
work in between is charged for it). While busy, frames are skipped, so with L > the
frame interval one step spans several frames.

Observation Space (Dict):
    ============== ========================== ==========================================
    key            space                      meaning
    ============== ========================== ==========================================
    image          Box(0, 255, (H, W, 3))     latest ego-camera frame, uint8 RGB
    image_prev     Box(0, 255, (H, W, 3))     the frame ``frame_stride`` frames before it
    ego_speed_mps  Box(0, 60, (1,))           the ego's own speed at capture [m/s]
    ego_yaw_rate_radps Box(-5, 5, (1,))       its yaw rate at capture [rad/s], + left
    pair_yaw_rad   Box(-pi, pi, (1,))         its heading change from image_prev's capture
                                              to image's [rad], + left (its yaw-rate
                                              sensor integrated)
    calibration    Box(-1e4, 1e4, (8,))       fx, fy, cx, cy [px], camera height [m],
                                              pitch [deg], bumper ahead of the camera [m],
                                              ego width [m]
    ============== ========================== ==========================================
    With a fovea (``camera.fovea_zoom``), also ``fovea_image`` and ``fovea_image_prev``
    (the same captures through the magnified view, ``fovea_width_share`` of the width) and ``fovea_calibration``
    (its 8 numbers, as ``calibration``).
    ``GeofenceObservation`` adds ``geofence`` (K, H, W) in [0, 1] and ``thresholds_s`` (K,),
    and with a fovea ``fovea_geofence`` (K, H, W).

Action Space: Box(0, 9, (1,)) — requested deceleration [m/s^2], applied through the
actuator model (0.1 s delay, 30 m/s^3 jerk limit) once it takes effect. A NaN,
negative or larger action is refused with a ValueError naming it.

Reward: -1 on the step of a collision, minus 0.01 per (m/s^2 * s) of commanded braking
(a mild comfort cost); 0 otherwise.

Episode End:
    terminated — 1 s after a collision, ego standstill with nothing closing in, or the
    threat resolved after braking, or every actor passed: wholly behind the ego and not
    gaining on it (see :meth:`sim.episode.ScenarioSim.done`).
    truncated — the scenario's ``duration_s`` is reached.

Ground truth (per-pixel eta/tau/flow/depth maps, per-actor gaps and TTCs, collision;
``fovea_gt`` the fovea's maps) travels in ``info``, never in the observation. The scenery seed is drawn from
``self.np_random``, so ``reset(seed=s)`` fixes every pixel. ``textures`` (a
``sim.textures.TextureStyle``) picks the ground and vehicle texture styles (detailed
ground and plain vehicles by default).
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from controllers.base import BrakeCommand
from controllers.stages import MAX_DECEL_MPS2
from sim.camera import CameraConfig
from sim.env_geofence import GeofenceObservation  # noqa: F401  (re-exported: the env's wrapper)
from sim.episode import ScenarioSim
from sim.latency import LatencyMode, parse_latency
from sim.loop import ClosedLoop
from sim.textures import TextureStyle
from sim.traffic import MAX_SPEED_MPS

MAX_YAW_RATE_RADPS = 5.0  # [rad/s] bound of the yaw-rate observation (a 12 m turn at 20 km/h: 0.46)
CALIBRATION_BOUND = 1e5  # [px or m or deg] bounds of the calibration vector's space (a fovea's focal too)


def _one_case(scenario: str):
    import scenarios

    cases = scenarios.resolve(scenario)
    if len(cases) != 1:
        raise ValueError(f"scenario {scenario!r} expands to {len(cases)} cases; name one case (e.g. {cases[0].name})")
    return cases[0]


def _calibration_vector(c) -> np.ndarray:
    """fx, fy, cx, cy [px], camera height [m], pitch [deg], bumper ahead of the camera [m], ego width [m]."""
    v = [c.fx_px, c.fy_px, c.cx_px, c.cy_px, c.mount_height_m, c.pitch_deg, c.bumper_ahead_m, c.ego_width_m]
    return np.array(v, np.float32)


class ScenarioEnv(gym.Env):
    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}

    def __init__(
        self,
        scenario: str = "CCRs-50",
        camera: CameraConfig | None = None,
        render_mode: str | None = None,
        textures: TextureStyle | None = None,
        latency: str | LatencyMode = "fixed:0",
        frame_stride: int = 1,
    ):
        self.case = _one_case(scenario)
        self.camera = camera or CameraConfig()
        if textures is not None and not isinstance(textures, TextureStyle):
            raise ValueError(f"textures={textures!r}: expected a sim.textures.TextureStyle")
        self.textures = textures or TextureStyle()
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode {render_mode!r} is not supported")
        self.latency = latency if isinstance(latency, LatencyMode) else parse_latency(latency)
        from controllers.geofence import check_frame_stride

        self.frame_stride = check_frame_stride(frame_stride)
        # the work a profile charges per step, set by a wrapper that runs an estimator (sim.latency)
        self.num_alphas = 0  # thresholds per view
        self.views = 1
        self.estimator_kind: str | None = None
        self.cached_frames = 0
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_fps": self.camera.fps_hz}
        h, w = self.camera.height_px, self.camera.width_px
        image = spaces.Box(0, 255, (h, w, 3), np.uint8)
        calibration = spaces.Box(-CALIBRATION_BOUND, CALIBRATION_BOUND, (8,), np.float32)
        obs = {
            "image": image,
            "image_prev": image,
            "ego_speed_mps": spaces.Box(0.0, MAX_SPEED_MPS, (1,), np.float32),
            "ego_yaw_rate_radps": spaces.Box(-MAX_YAW_RATE_RADPS, MAX_YAW_RATE_RADPS, (1,), np.float32),
            "pair_yaw_rad": spaces.Box(-math.pi, math.pi, (1,), np.float32),
            "calibration": calibration,
        }
        if self.camera.fovea_zoom is not None:
            fovea = spaces.Box(0, 255, (h, self.camera.fovea_width_px, 3), np.uint8)  # narrower: sim.camera
            obs |= {"fovea_image": fovea, "fovea_image_prev": fovea, "fovea_calibration": calibration}
        self.observation_space = spaces.Dict(obs)
        self.action_space = spaces.Box(0.0, MAX_DECEL_MPS2, (1,), np.float32)
        self._sim: ScenarioSim | None = None
        self._loop: ClosedLoop | None = None
        self._charged_s = 0.0
        self._handed_out_s: float | None = None  # wall time [s] the current observation was returned

    def charge(self, compute_s: float) -> None:
        """Add ``compute_s`` [s] of compute to the current step's job (``measured`` latency)."""
        self._charged_s += float(compute_s)

    def _obs(self) -> dict:
        o = self._loop.observation(self._job)
        out = {
            "image": o.image_latest.copy(),
            "image_prev": o.image_prev.copy(),
            "ego_speed_mps": np.array([min(o.ego_speed_mps, MAX_SPEED_MPS)], np.float32),
            "ego_yaw_rate_radps": np.clip([o.ego_yaw_rate_radps], -MAX_YAW_RATE_RADPS, MAX_YAW_RATE_RADPS).astype(
                np.float32
            ),
            "pair_yaw_rad": np.array([o.pair_rotation_rad], np.float32),
            "calibration": _calibration_vector(o.calibration),
        }
        if o.calibration.fovea is not None:
            out["fovea_image"] = o.fovea_latest.copy()
            out["fovea_image_prev"] = o.fovea_prev.copy()
            out["fovea_calibration"] = _calibration_vector(o.calibration.fovea)
        return out

    def _info(self) -> dict:
        """Ground truth at the observed frame's capture, as plain dicts and arrays:
        per-actor truth, the critical actor, the collision, the per-pixel maps."""
        truth = self._loop.truth_at(self._job)
        info = {
            "t_s": truth.t_s,
            "actors": [asdict(a) for a in truth.actors],
            "critical": asdict(truth.critical) if truth.critical is not None else None,
            "collision": asdict(truth.collision) if truth.collision is not None else None,
        }
        gt = self._loop.ground_truth(self._job.frame)
        if gt is not None:
            info["gt"] = asdict(gt)
        if self.camera.fovea_zoom is not None:
            fgt = self._loop.ground_truth(self._job.frame, "fovea")
            if fgt is not None:
                info["fovea_gt"] = asdict(fgt)
        return info

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        options = options or {}
        unknown = sorted(set(options) - {"scenario"})
        if unknown:
            raise ValueError(f"reset option {unknown[0]!r} is unknown (known: scenario)")
        if "scenario" in options:
            self.case = _one_case(options["scenario"])
        self.close()
        world_seed = int(self.np_random.integers(2**31 - 1))
        self._sim = ScenarioSim(self.case, self.camera, world_seed, render=True, textures=self.textures)
        self._loop = ClosedLoop(
            self._sim,
            self.latency,
            num_alphas=self.num_alphas,
            pairs=True,
            frame_stride=self.frame_stride,
            estimator=self.estimator_kind,
            views=self.views,
            cached_frames=self.cached_frames,
        )
        self._charged_s = 0.0
        self._job = self._loop.reset()
        self._last = (self._obs(), self._info())
        self._handed_out_s = time.perf_counter()
        return self._last

    def step(self, action):
        if self._loop is None:
            raise RuntimeError("call reset() before step()")
        if self._loop.end_reason is not None:
            raise RuntimeError("the episode has ended: call reset()")
        a = np.asarray(action, dtype=np.float64).reshape(-1)
        if a.size != 1 or not np.isfinite(a[0]) or not 0.0 <= a[0] <= MAX_DECEL_MPS2:
            raise ValueError(
                f"action {np.asarray(action).tolist()!r}: expected one finite deceleration in "
                f"[0, {MAX_DECEL_MPS2:g}] m/s^2"
            )
        had_collision = self._sim.collision is not None
        brake0 = self._loop.brake_integral
        # the time since the observation was handed out, less what a wrapper charged inside it
        since_s = time.perf_counter() - self._handed_out_s if self._handed_out_s is not None else 0.0
        agent_s = max(since_s - self._charged_s, 0.0)
        job = self._loop.submit(BrakeCommand(float(a[0])), self._charged_s + agent_s, who="agent")
        self._charged_s = 0.0
        reward = -0.01 * (self._loop.brake_integral - brake0)
        if self._sim.collision is not None and not had_collision:
            reward -= 1.0
        reason = self._loop.end_reason
        if job is not None:
            self._job = job
            self._last = (self._obs(), self._info())
        obs, info = self._last
        obs = {k: v.copy() for k, v in obs.items()}
        info = {**info, "end_reason": reason}
        self._handed_out_s = time.perf_counter()
        terminated = reason in ("collision", "standstill", "resolved", "passed")
        return obs, float(reward), terminated, reason == "duration", info

    def render(self):
        if self.render_mode == "rgb_array" and self._last is not None:
            return self._last[0]["image"]
        return None

    def close(self):
        if self._sim is not None:
            self._sim.close()
            self._sim = None
            self._loop = None
