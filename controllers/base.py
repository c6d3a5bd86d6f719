"""The controller interface: what a braking policy sees and what it returns.

A controller is called once per camera frame. It observes the camera image and the
ego's own speed (:class:`Observation`). Ground truth (:class:`sim.episode.StepTruth`)
is passed separately and only controllers that declare ``uses_ground_truth`` may read
it: the oracle is the upper bound, not a deployable policy.

The command is a requested deceleration [m/s^2] (>= 0) and a warning flag. The
simulator applies it ``compute_latency_s`` after the frame's capture (the policy's
own compute time, charged to the reaction time), then through the actuator model.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Observation:
    t_s: float  # capture time of the latest frame [s]
    ego_speed_mps: float  # [m/s]
    image_latest: np.ndarray | None  # (H, W, 3) uint8, None when the controller needs no camera
    image_prev: np.ndarray | None  # the frame before, same format
    dt_s: float  # frame interval [s]


@dataclass(frozen=True)
class BrakeCommand:
    decel_mps2: float = 0.0  # requested deceleration [m/s^2], >= 0
    warning: bool = False  # forward-collision warning on
    compute_latency_s: float = 0.0  # time the policy took to decide [s]


class Controller(ABC):
    """Observation (+ truth for oracles) -> brake command."""

    name: str = "controller"
    needs_camera: bool = False
    uses_ground_truth: bool = False

    def reset(self) -> None:
        """Forget any state from a previous run."""

    @abstractmethod
    def act(self, obs: Observation, truth) -> BrakeCommand:
        """Decide from the latest observation. ``truth`` is for oracles only."""
