"""What a scenario run hands out: the captured ``Frame``, the ground truth ``StepTruth`` at
it, and the ``Collision`` that ends the run."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from sim.actor_truth import ActorTruth
from sim.ground_truth import GroundTruth

if TYPE_CHECKING:  # the world imports PyBullet, which a run without a camera never needs
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
