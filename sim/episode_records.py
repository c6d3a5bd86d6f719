"""What a scenario run hands out: the captured ``Frame``, the ground truth ``StepTruth`` at
it, and the ``Collision`` that ends the run; and the closed loop's ``FrameRecord`` of each
captured frame (``sim.loop``)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from sim.actor_truth import ActorTruth
from sim.ground_truth import GroundTruth

if TYPE_CHECKING:  # the world imports PyBullet, which a run without a camera never needs
    from controllers.base import BrakeCommand
    from sim.latency import JobWork
    from sim.world import Render


@dataclass(frozen=True)
class Collision:
    t_s: float
    instance: int
    impact_speed_mps: float  # ego speed at first contact [m/s]
    relative_impact_speed_mps: float  # ego minus actor speed along the ego's heading [m/s]


@dataclass
class StepTruth:
    """Ground truth at a frame. Never part of what a (non-oracle) policy observes."""

    t_s: float
    ego_speed_mps: float
    actors: list[ActorTruth]
    critical: ActorTruth | None  # in-path actor ahead with the smallest TTC
    # per-pixel maps of each view against the frame before, filled by the loop only for a
    # controller that asks for them (``Controller.uses_pixel_truth``)
    pixels: dict[str, GroundTruth] | None = None
    collision: Collision | None = None


@dataclass
class Frame:
    """A captured frame: the wide view's image (H, W, 3) uint8, exact depth and instances,
    the fovea's render (``sim.world.Render``, same pose) when the camera has one, and the
    poses (world x [m], y [m], heading [rad]) of every actor at capture time. Road users'
    rigid parts: ``part`` (the wide view's part ids, ``sim.world.Render.part``) and
    ``part_poses`` (part id -> world_T_part, 4x4)."""

    t_s: float
    image: np.ndarray | None
    cam_T_world: np.ndarray
    poses: dict[int, tuple[float, float, float]] = field(default_factory=dict)
    depth_m: np.ndarray | None = None
    instance: np.ndarray | None = None
    fovea: Render | None = None
    part: np.ndarray | None = None
    part_poses: dict[int, np.ndarray] = field(default_factory=dict)

    def parts(self, name: str) -> np.ndarray | None:
        """The part ids of view 'wide' or 'fovea' (None where no road user was rendered)."""
        if name == "wide":
            return self.part
        return self.fovea.part if self.fovea is not None else None

    def view(self, name: str) -> tuple[np.ndarray | None, np.ndarray | None, np.ndarray | None]:
        """(image, depth_m, instance) of view 'wide' or 'fovea' (Nones where not rendered)."""
        if name == "wide":
            return self.image, self.depth_m, self.instance
        if self.fovea is None:
            return None, None, None
        return self.fovea.rgb, self.fovea.depth_m, self.fovea.instance


@dataclass
class FrameRecord:
    """One captured frame: what happened to it, and the state at its capture."""

    index: int
    t_s: float  # [s] capture time
    ego_speed_mps: float
    ego_accel_mps2: float
    truth: StepTruth  # ground truth at capture (never shown to a deployable policy)
    active: BrakeCommand  # the command in effect at capture
    status: str = "pending"  # processed | skipped | unpaired | unused (see sim.loop's docstring)
    latency_s: float | None = None  # [s] estimator latency of its job
    wait_s: float | None = None  # [s] from capture to the start of its job
    decided: BrakeCommand | None = None  # its job's command
    work: JobWork | None = None  # what its job computed (what a profile charges)
    fence_cover: dict = field(default_factory=dict)  # view -> threshold '<s>' -> share of the critical actor inside
    ego_yaw_rate_radps: float = 0.0  # [rad/s] + left, as the car's yaw-rate sensor reads it
    ego_heading_rad: float = 0.0  # [rad] + left, exact (what the car's yaw-rate sensor integrates to)
