"""Paths of a scenario, as plain data (no simulator imports): the ego's nominal path
(straight, or turning left or right at the junction) and where crossing and turning-
traffic targets start so that they meet it.

Convention: world frame, x along the main road, y left, headings about z [rad]. The
ego's footprint centre starts at the origin heading +x; ``s`` [m] is the distance its
centre has travelled along its path. Right-hand traffic: a left turn crosses the
oncoming lane into the cross road's lane heading +y; a right turn goes into the lane
heading -y.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from scenarios.road import RoadConfig

TURNS = ("straight", "left", "right")
PATH_STEP_M = 0.05  # [m] sampling of a path when searching for a conflict point


@dataclass(frozen=True)
class EgoPath:
    """The ego's path: straight along y = 0, or a quarter circle of ``radius_m`` into the
    cross road at ``junction_x_m``, then straight on."""

    turn: str = "straight"
    junction_x_m: float | None = None
    radius_m: float = 12.0
    lane_width_m: float = 3.5

    def __post_init__(self) -> None:
        if self.turn not in TURNS:
            raise ValueError(f"EgoPath.turn = {self.turn!r}: one of {', '.join(TURNS)}")
        if self.turn != "straight" and self.junction_x_m is None:
            raise ValueError("EgoPath: a turn needs a junction")

    @property
    def sign(self) -> float:
        """+1 turning left, -1 turning right, 0 straight."""
        return {"straight": 0.0, "left": 1.0, "right": -1.0}[self.turn]

    @property
    def turn_start_s(self) -> float:
        """[m] path length (= x) where the arc begins; +inf when going straight."""
        if self.turn == "straight":
            return math.inf
        return self.junction_x_m + self.sign * self.lane_width_m / 2 - self.radius_m

    def pose_at(self, s_m: float) -> tuple[float, float, float]:
        """(x, y, heading) of the ego's centre after ``s_m`` metres along the path."""
        s0 = self.turn_start_s
        if s_m <= s0:
            return float(s_m), 0.0, 0.0
        R, k = self.radius_m, self.sign
        arc = R * math.pi / 2
        if s_m <= s0 + arc:
            th = (s_m - s0) / R
            return s0 + R * math.sin(th), k * R * (1 - math.cos(th)), k * th
        return s0 + R, k * (R + (s_m - s0 - arc)), k * math.pi / 2

    def closest_s(self, x_m: float, y_m: float) -> float:
        """Path length [m] of the path's point nearest (x, y) (the first straight, the arc
        and the last straight each projected in closed form)."""
        s0 = self.turn_start_s
        if self.turn == "straight":
            return float(x_m)
        R, k = self.radius_m, self.sign
        cands = [min(x_m, s0)]
        th = min(max(math.atan2(x_m - s0, -k * (y_m - k * R)), 0.0), math.pi / 2)
        cands.append(s0 + R * th)
        cands.append(s0 + R * math.pi / 2 + max(k * y_m - R, 0.0))
        return min(cands, key=lambda s: math.dist(self.pose_at(s)[:2], (x_m, y_m)))

    def first_crossing_s(self, point_m, heading_rad: float, max_s_m: float) -> float | None:
        """Path length [m] where the path first meets the line through ``point_m`` with
        ``heading_rad`` (None if not within ``max_s_m``)."""
        n = np.array([-math.sin(heading_rad), math.cos(heading_rad)])  # the line's normal
        ss = np.arange(0.0, max_s_m, PATH_STEP_M)
        pts = np.array([self.pose_at(s)[:2] for s in ss])
        side = (pts - np.asarray(point_m)) @ n
        hit = np.flatnonzero(np.sign(side[1:]) != np.sign(side[:-1]))
        return None if hit.size == 0 else float(ss[hit[0] + 1])


def ego_path(turn: str, road: RoadConfig, radius_m: float) -> EgoPath:
    return EgoPath(turn, road.junction_m, radius_m, road.lane_width_m)


def path_leaves_road(path: EgoPath, road: RoadConfig, length_m: float) -> tuple[float, float] | None:
    """The first point (x, y) [m] of the path's first ``length_m`` that is off the
    carriageways of ``road`` (None: it stays on them)."""
    for s in np.arange(0.0, length_m, 0.5):
        x, y, _ = path.pose_at(float(s))
        if not road.on_road(x, y):
            return x, y
    return None


def crossing_lane(direction: str, road: RoadConfig) -> tuple[float, float]:
    """(x of the lane centre [m], heading [rad]) of a car crossing the junction from the
    ego's left ('from_left', heading -y) or right ('from_right', heading +y)."""
    hw = road.lane_width_m / 2
    if direction == "from_left":
        return road.junction_m - hw, -math.pi / 2
    return road.junction_m + hw, math.pi / 2


def meet_start(point_m, heading_rad: float, speed_mps: float, arrive_s: float) -> tuple[float, float]:
    """Start (x, y) [m] of a target moving at ``speed_mps`` along ``heading_rad`` from t = 0
    that passes ``point_m`` at ``arrive_s``."""
    d = speed_mps * arrive_s
    return point_m[0] - d * math.cos(heading_rad), point_m[1] - d * math.sin(heading_rad)
