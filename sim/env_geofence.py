"""``GeofenceObservation``: the Gymnasium wrapper that adds an estimator's geofences to
``sim.env.ScenarioEnv``'s observations and charges their compute as latency."""

from __future__ import annotations

import time

import gymnasium as gym
import numpy as np
from gymnasium import spaces


class GeofenceObservation(gym.Wrapper):
    """Adds an estimator's K geofences of every observed pair to the observation, and
    charges the estimator's compute to the step's job (``measured`` latency) and its K to
    the env (``profile`` latency): latency as in ``bittc run``.

    ``estimator``: a name for ``bittc_core.estimator.make_estimator`` ("bittc", "flow") or
    an ``Estimator``; ``thresholds_s`` (camera-plane TTC [s], any order) or
    ``num_alphas`` (``controllers.geofence.default_thresholds``)."""

    def __init__(self, env: gym.Env, estimator="bittc", thresholds_s=None, num_alphas: int | None = None):
        super().__init__(env)
        from bittc_core.estimator import make_estimator
        from controllers.geofence import check_thresholds, default_thresholds, estimator_thresholds

        if thresholds_s is not None and num_alphas is not None:
            raise ValueError("give thresholds_s or num_alphas, not both")
        self.estimator = make_estimator(estimator) if isinstance(estimator, str) else estimator
        thr = check_thresholds(thresholds_s) if thresholds_s is not None else default_thresholds(num_alphas or 4)
        base = env.unwrapped
        self.thresholds_s = np.asarray(thr, np.float32)
        self._thr_est = estimator_thresholds(self.estimator, thr, base.camera.dt_s, base.frame_stride)
        base.num_alphas = len(thr)
        # one estimator per view, each its own frame cache (the model shared)
        self._views = {"geofence": ("image_prev", "image", self.estimator)}
        if base.camera.fovea_zoom is not None:
            fork = getattr(self.estimator, "fork", None)
            self._views["fovea_geofence"] = ("fovea_image_prev", "fovea_image", fork() if fork else self.estimator)
        base.views = len(self._views)
        base.estimator_kind = getattr(self.estimator, "name", None) or None
        base.cached_frames = int(getattr(self.estimator, "cached_frames", 0))
        k = len(thr)
        width = {"geofence": base.camera.width_px, "fovea_geofence": base.camera.fovea_width_px}
        self.observation_space = spaces.Dict(
            {
                **env.observation_space.spaces,
                **{
                    key: spaces.Box(0.0, 1.0, (k, base.camera.height_px, width[key]), np.float32) for key in self._views
                },
                "thresholds_s": spaces.Box(0.0, float(max(thr)), (k,), np.float32),
            }
        )

    def _augment(self, obs: dict) -> dict:
        t0 = time.perf_counter()
        self._maps = {}
        for key, (prev, latest, est) in self._views.items():
            maps = est.geofence(obs[prev], obs[latest], self._thr_est)
            self._maps[key] = np.clip(maps, 0.0, 1.0).astype(np.float32)
        self.env.unwrapped.charge(time.perf_counter() - t0)
        return {**obs, **self._maps, "thresholds_s": self.thresholds_s.copy()}

    def reset(self, **kwargs):
        for _, _, est in self._views.values():
            if hasattr(est, "reset"):
                est.reset()
        obs, info = self.env.reset(**kwargs)
        return self._augment(obs), info

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        if terminated or truncated:  # the run has ended: the last observation again
            last = {**obs, **{k: v.copy() for k, v in self._maps.items()}, "thresholds_s": self.thresholds_s.copy()}
            return last, reward, terminated, truncated, info
        return self._augment(obs), reward, terminated, truncated, info
