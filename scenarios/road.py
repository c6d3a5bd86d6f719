"""The straight road of a scenario, as plain data (no simulator imports): validated by
``scenarios.spec``, built by ``sim.scenery``. Lengths in metres, x along the road, y left."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class RoadConfig:
    """Straight road layout [m]."""

    lanes_left: int = 1  # lanes left of the ego's lane
    lanes_right: int = 1  # lanes right of the ego's lane
    lane_width_m: float = 3.5
    x_start_m: float = -60.0
    x_end_m: float = 600.0
    segment_m: float = 20.0  # road/barrier tile length (keeps texture scale sane)
    roadside_spacing_m: float = 25.0  # mean spacing of poles/trees/buildings per side
    barrier: bool = True
    buildings: bool = True
    markings_max_x_m: float | None = None  # no dashed markings beyond this x [m] (None: whole road)

    def __post_init__(self) -> None:
        if self.lanes_left < 0 or self.lanes_right < 0 or self.lanes_left + self.lanes_right > 6:
            raise ValueError(
                f"RoadConfig lanes_left={self.lanes_left}, lanes_right={self.lanes_right}: need 0..6 in total"
            )
        if not 2.5 <= self.lane_width_m <= 5.0:
            raise ValueError(f"RoadConfig.lane_width_m = {self.lane_width_m} outside [2.5, 5.0] m")
        if not self.x_end_m > self.x_start_m + self.segment_m:
            raise ValueError(f"RoadConfig x range [{self.x_start_m}, {self.x_end_m}] m is too short")

    @property
    def y_left_edge_m(self) -> float:
        return (self.lanes_left + 0.5) * self.lane_width_m

    @property
    def y_right_edge_m(self) -> float:
        return -(self.lanes_right + 0.5) * self.lane_width_m

    def lane_center_y_m(self, lane: int) -> float:
        if not -self.lanes_right <= lane <= self.lanes_left:
            raise ValueError(f"lane {lane} does not exist (lanes {-self.lanes_right}..{self.lanes_left})")
        return lane * self.lane_width_m
