"""The road of a scenario, as plain data (no simulator imports): validated by
``scenarios.spec``, built by ``sim.scenery``. Lengths in metres, x along the road, y left.

A straight main road along x; optionally sidewalks with kerbs on both sides
(``sidewalk_m``) and a four-way junction: a cross road along y whose centreline lies at
x = ``junction_m``, one lane each way of ``lane_width_m`` (right-hand traffic: the lane
heading +y at x = junction_m + lane_width_m / 2)."""

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
    sidewalk_m: float = 0.0  # [m] sidewalk width on each side, behind a kerb (0: verges and barriers)
    junction_m: float | None = None  # [m] x of a cross road's centreline (None: no junction)

    def __post_init__(self) -> None:
        if self.lanes_left < 0 or self.lanes_right < 0 or self.lanes_left + self.lanes_right > 6:
            raise ValueError(
                f"RoadConfig lanes_left={self.lanes_left}, lanes_right={self.lanes_right}: need 0..6 in total"
            )
        if not 2.5 <= self.lane_width_m <= 5.0:
            raise ValueError(f"RoadConfig.lane_width_m = {self.lane_width_m} outside [2.5, 5.0] m")
        if not 0.0 <= self.sidewalk_m <= 6.0:
            raise ValueError(f"RoadConfig.sidewalk_m = {self.sidewalk_m} outside [0, 6] m")
        if self.junction_m is not None and not self.x_start_m + 30.0 <= self.junction_m <= self.x_end_m - 30.0:
            raise ValueError(f"RoadConfig.junction_m = {self.junction_m} m is not on the road")
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

    @property
    def cross_half_width_m(self) -> float:
        """[m] half the width of the cross road's carriageway (one lane each way)."""
        return self.lane_width_m

    def on_road(self, x_m: float, y_m: float, fillet_m: float = 6.0) -> bool:
        """True where (x, y) lies on a carriageway: the main road, the cross road, or a
        junction corner within ``fillet_m`` of both (the rounded kerbs a turn sweeps)."""
        on_main = self.y_right_edge_m <= y_m <= self.y_left_edge_m and self.x_start_m <= x_m <= self.x_end_m
        if on_main or self.junction_m is None:
            return on_main
        dx = abs(x_m - self.junction_m) - self.cross_half_width_m
        dy = max(y_m - self.y_left_edge_m, self.y_right_edge_m - y_m, 0.0)
        return dx <= 0.0 or (dx <= fillet_m and dy <= fillet_m)

    def on_foot_area(self, x_m: float, y_m: float) -> bool:
        """True where a pedestrian or cyclist may be: a carriageway or a sidewalk."""
        w = self.sidewalk_m
        on_main = self.y_right_edge_m - w <= y_m <= self.y_left_edge_m + w
        on_cross = self.junction_m is not None and abs(x_m - self.junction_m) <= self.cross_half_width_m + w
        return self.x_start_m <= x_m <= self.x_end_m and (on_main or on_cross)
