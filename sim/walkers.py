"""Scripted road users: a pedestrian or cyclist moving along a straight line, in closed form.

A walker waits at its start until ``start_s``, then moves at ``speed_mps`` along its
heading; with ``stop_after_m`` it brakes at ``stop_decel_mps2`` so that it comes to rest
having moved exactly that far (a pedestrian who stops at the kerb). Every state is a
closed-form function of time, so the oracle can read its exact future
(``pose_at``) and the ground truth its exact gait phase (``travelled_at``).

It offers what the simulator reads from a highway-env vehicle (``world_pose``,
``world_velocity``, ``speed``, ``current_accel_mps2``, ``LENGTH``/``WIDTH``, ``command``
and ``step``) but drives no highway-env road: it is stepped beside the traffic.

Convention: world frame, x along the road, y left, heading about z [rad]; times [s]
from the start of the run.
"""

from __future__ import annotations

import math

import numpy as np


class Walker:
    def __init__(
        self,
        x_m: float,
        y_m: float,
        heading_rad: float,
        speed_mps: float,
        length_m: float,
        width_m: float,
        start_s: float = 0.0,
        stop_after_m: float | None = None,
        stop_decel_mps2: float = 2.0,
    ):
        if speed_mps <= 0:
            raise ValueError(f"Walker speed {speed_mps} m/s: must be > 0")
        self.x0, self.y0, self.heading = float(x_m), float(y_m), float(heading_rad)
        self.v = float(speed_mps)
        self.LENGTH, self.WIDTH = float(length_m), float(width_m)
        self.start_s = float(start_s)
        self.stop_after_m = None if stop_after_m is None else float(stop_after_m)
        self.decel = float(stop_decel_mps2)
        # distance at which braking starts (0 when the stop is nearer than the braking distance)
        self.brake_at_m = math.inf if stop_after_m is None else max(stop_after_m - self.v**2 / (2 * self.decel), 0.0)
        self.t_s = 0.0
        self.halted = False  # set on contact: it stays where it is

    # ------------------------------------------------------------------ closed form
    def _braking_from_s(self) -> float:
        return self.start_s + self.brake_at_m / self.v

    def travelled_at(self, t_s: float) -> float:
        """Distance moved [m] at time ``t_s``."""
        if t_s <= self.start_s:
            return 0.0
        tb = self._braking_from_s()
        if t_s <= tb:
            return self.v * (t_s - self.start_s)
        v0 = min(self.v, math.sqrt(2 * self.decel * self.stop_after_m))  # speed when braking starts
        tau = min(t_s - tb, v0 / self.decel)
        return self.brake_at_m + v0 * tau - 0.5 * self.decel * tau**2

    def speed_at(self, t_s: float) -> float:
        if t_s < self.start_s:
            return 0.0
        tb = self._braking_from_s()
        if t_s < tb:
            return self.v
        v0 = min(self.v, math.sqrt(2 * self.decel * self.stop_after_m))
        return max(v0 - self.decel * (t_s - tb), 0.0)

    def pose_at(self, t_s: float) -> tuple[float, float, float]:
        """(x [m], y [m], heading [rad]) at time ``t_s`` as scripted."""
        d = self.travelled_at(t_s)
        return self.x0 + d * math.cos(self.heading), self.y0 + d * math.sin(self.heading), self.heading

    # ------------------------------------------------------------------ the vehicle interface
    @property
    def travelled_m(self) -> float:
        return self.travelled_at(self._t_frozen if self.halted else self.t_s)

    @property
    def speed(self) -> float:
        return 0.0 if self.halted else self.speed_at(self.t_s)

    @speed.setter
    def speed(self, value: float) -> None:  # a contact stops it (see ScenarioSim._check_collision)
        if value == 0.0 and not self.halted:
            self.halted, self._t_frozen = True, self.t_s

    @property
    def current_accel_mps2(self) -> float:
        if self.halted or self.t_s < self.start_s:
            return 0.0
        return -self.decel if self.speed_at(self.t_s) < self.v and self.t_s >= self._braking_from_s() else 0.0

    def world_pose(self) -> tuple[float, float, float]:
        return self.pose_at(self._t_frozen if self.halted else self.t_s)

    def world_velocity(self) -> np.ndarray:
        return np.array([math.cos(self.heading), math.sin(self.heading)]) * self.speed

    def command(self, t_s: float, dt_s: float) -> None:
        """Scripted: nothing to decide."""

    def step(self, dt_s: float) -> None:
        self.t_s = round(self.t_s + dt_s, 9)
