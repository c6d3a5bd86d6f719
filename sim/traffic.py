"""Traffic and vehicle kinematics, run by highway-env headless.

highway-env's planar frame has y pointing right (screen down); ours has y left. Every
pose crossing this module's boundary is converted: y_world = -y_hw,
heading_world = -heading_hw. Inside, vehicles are highway-env ``Vehicle`` (kinematic
bicycle) or ``IDMVehicle`` objects stepped at the simulation rate.
"""

from __future__ import annotations

import math
import os
from collections import deque
from dataclasses import dataclass

import numpy as np

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")  # highway_env imports pygame
os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
from highway_env.road.lane import LineType, StraightLane  # noqa: E402
from highway_env.road.road import Road, RoadNetwork  # noqa: E402
from highway_env.vehicle.behavior import IDMVehicle  # noqa: E402
from highway_env.vehicle.kinematics import Vehicle  # noqa: E402

from controllers.stages import MAX_DECEL_MPS2  # noqa: E402
from sim.scenery import RoadConfig  # noqa: E402

MAX_SPEED_MPS = 60.0  # [m/s] above any scenario's speeds
LATERAL_GAIN_PER_S = 1.5  # [1/s] lateral error -> heading correction
HEADING_GAIN = 3.0  # [-] heading error -> steering


@dataclass(frozen=True)
class ActuatorConfig:
    """Ego brake actuator: pure delay, then a jerk-limited approach to the command."""

    delay_s: float = 0.1  # [s] command -> start of deceleration build-up
    max_decel_mps2: float = MAX_DECEL_MPS2  # [m/s^2] full braking on dry asphalt
    jerk_mps3: float = 30.0  # [m/s^3] rate limit of the deceleration

    def __post_init__(self) -> None:
        if self.delay_s < 0 or self.max_decel_mps2 <= 0 or self.jerk_mps3 <= 0:
            raise ValueError(f"ActuatorConfig needs delay_s >= 0, max_decel_mps2 > 0, jerk_mps3 > 0; got {self}")


def build_road(cfg: RoadConfig, seed: int) -> Road:
    """A highway-env road: one straight lane per lane of ``cfg``, all in +x."""
    net = RoadNetwork()
    for k in range(-cfg.lanes_right, cfg.lanes_left + 1):
        y_hw = -cfg.lane_center_y_m(k)
        left_edge = LineType.CONTINUOUS_LINE if k == cfg.lanes_left else LineType.STRIPED
        right_edge = LineType.CONTINUOUS_LINE if k == -cfg.lanes_right else LineType.NONE
        lane = StraightLane(
            [cfg.x_start_m, y_hw],
            [cfg.x_end_m, y_hw],
            width=cfg.lane_width_m,
            line_types=(left_edge, right_edge),
            speed_limit=MAX_SPEED_MPS,
        )
        net.add_lane("a", "b", lane)
    return Road(network=net, np_random=np.random.RandomState(seed), record_history=False)


class _Sized:
    """Mixin: per-instance footprint and planar pose in the world frame."""

    def set_size(self, length_m: float, width_m: float) -> None:
        self.LENGTH = length_m  # instance attributes shadow the class constants
        self.WIDTH = width_m
        self.MAX_SPEED = MAX_SPEED_MPS
        self.MIN_SPEED = 0.0

    def world_pose(self) -> tuple[float, float, float]:
        """(x [m], y [m], heading [rad]) in the world frame (y left)."""
        return float(self.position[0]), -float(self.position[1]), -float(self.heading)

    def world_velocity(self) -> np.ndarray:
        """(vx, vy) [m/s] in the world frame."""
        return np.array([math.cos(self.heading), -math.sin(self.heading)]) * self.speed


class ScriptedVehicle(_Sized, Vehicle):
    """A vehicle following a scripted speed profile and lateral path.

    Longitudinal: constant speed, then from ``brake_onset_s`` a constant
    ``accel_mps2`` (negative brakes); it stops at standstill instead of reversing.
    Lateral: tracks ``y_target_m(t)`` (world frame) with a steering law on the
    bicycle model; a lane change follows a smooth cosine profile. With
    ``keep_lateral=False`` it drives straight along its initial heading (crossing
    traffic, drifting vehicles).
    """

    def __init__(
        self,
        road: Road,
        x_m: float,
        y_m: float,
        heading_rad: float,
        speed_mps: float,
        length_m: float,
        width_m: float,
        accel_mps2: float = 0.0,
        brake_onset_s: float = 0.0,
        lane_change: tuple[float, float, float] | None = None,
        max_speed_mps: float = MAX_SPEED_MPS,
        keep_lateral: bool = True,
    ):
        super().__init__(road, np.array([x_m, -y_m], float), -heading_rad, speed_mps)
        self.set_size(length_m, width_m)
        self.accel_mps2 = accel_mps2
        self.brake_onset_s = brake_onset_s
        self.y0_m = y_m
        self.lane_change = lane_change  # (start [s], duration [s], target y [m])
        self.max_speed_mps = max_speed_mps
        self.keep_lateral = keep_lateral  # False: drive straight along the initial heading
        self.current_accel_mps2 = 0.0

    def y_target_m(self, t_s: float) -> tuple[float, float]:
        """Target lateral position [m] and its rate [m/s] at time t (world frame)."""
        if self.lane_change is None:
            return self.y0_m, 0.0
        t0, dur, y1 = self.lane_change
        if t_s <= t0:
            return self.y0_m, 0.0
        if t_s >= t0 + dur:
            return y1, 0.0
        ph = (t_s - t0) / dur
        y = self.y0_m + (y1 - self.y0_m) * 0.5 * (1 - math.cos(math.pi * ph))
        dy = (y1 - self.y0_m) * 0.5 * math.pi / dur * math.sin(math.pi * ph)
        return y, dy

    def command(self, t_s: float, dt_s: float) -> None:
        a = self.accel_mps2 if t_s >= self.brake_onset_s else 0.0
        if self.speed + a * dt_s < 0.0:
            a = -self.speed / dt_s
        if self.speed + a * dt_s > self.max_speed_mps:
            a = (self.max_speed_mps - self.speed) / dt_s
        self.current_accel_mps2 = a
        steering = _lateral_steering(self, *self.y_target_m(t_s)) if self.keep_lateral else 0.0
        self.action = {"acceleration": a, "steering": steering}


class EgoVehicle(_Sized, Vehicle):
    """The ego: lane keeping on its start lane (or, with ``path``, pure pursuit along that
    ``scenarios.paths.EgoPath``), braking through an actuator model. ``yaw_rate_radps``: its
    yaw rate in the world frame [rad/s] (+ turning left) over the last step, as a car's
    yaw-rate sensor reads it."""

    def __init__(
        self,
        road: Road,
        x_m: float,
        y_m: float,
        speed_mps: float,
        length_m: float,
        width_m: float,
        actuator: ActuatorConfig,
        sim_dt_s: float,
        path=None,
    ):
        super().__init__(road, np.array([x_m, -y_m], float), 0.0, speed_mps)
        self.set_size(length_m, width_m)
        self.path = path
        self.yaw_rate_radps = 0.0
        self.actuator = actuator
        self.y_lane_m = y_m
        n_delay = int(round(actuator.delay_s / sim_dt_s))
        self._pipe: deque[float] = deque([0.0] * n_delay)
        self.current_accel_mps2 = 0.0
        self.command_decel_mps2 = 0.0

    def command(self, decel_cmd_mps2: float, dt_s: float) -> None:
        """Advance the actuator by one step with a requested deceleration [m/s^2] (>= 0)."""
        act = self.actuator
        self.command_decel_mps2 = min(max(decel_cmd_mps2, 0.0), act.max_decel_mps2)
        self._pipe.append(self.command_decel_mps2)
        target = -self._pipe.popleft()
        step = act.jerk_mps3 * dt_s
        a = self.current_accel_mps2 + float(np.clip(target - self.current_accel_mps2, -step, step))
        self.current_accel_mps2 = a
        applied = a if self.speed + a * dt_s >= 0.0 else -self.speed / dt_s
        if self.path is None or self.path.turn == "straight":
            steering = _lateral_steering(self, self.y_lane_m, 0.0)
        else:
            steering = _pursuit_steering(self, self.path)
        self.action = {"acceleration": applied, "steering": steering}
        beta = math.atan(0.5 * math.tan(steering))  # highway-env's bicycle model, mirrored
        self.yaw_rate_radps = -float(self.speed) * math.sin(beta) / (self.LENGTH / 2)


class TrafficVehicle(_Sized, IDMVehicle):
    """Background traffic: highway-env's IDM car-following on its lane, no lane changes."""

    def __init__(self, road: Road, x_m: float, y_m: float, speed_mps: float, length_m: float, width_m: float):
        super().__init__(
            road, np.array([x_m, -y_m], float), 0.0, speed_mps, target_speed=speed_mps, enable_lane_change=False
        )
        self.set_size(length_m, width_m)
        self.current_accel_mps2 = 0.0  # [m/s^2] along the heading, as applied in the last step

    def command(self, t_s: float, dt_s: float) -> None:
        self.act()
        a = float(self.action["acceleration"])
        if self.speed + a * dt_s < 0.0:  # stop at standstill instead of reversing
            a = -self.speed / dt_s
        if self.speed + a * dt_s > self.MAX_SPEED:
            a = (self.MAX_SPEED - self.speed) / dt_s
        self.action["acceleration"] = a
        self.current_accel_mps2 = a


def _lateral_steering(v: Vehicle, y_ref_m: float, dy_ref_mps: float) -> float:
    """Steering [rad] that tracks a world-frame lateral reference on a straight road."""
    y, heading = -v.position[1], -v.heading
    forward = 1.0 if math.cos(heading) >= 0 else -1.0
    speed = max(abs(v.speed), 1.0)
    # desired world heading: follow the reference's slope, correct the lateral error
    desired = math.atan2(dy_ref_mps + LATERAL_GAIN_PER_S * (y_ref_m - y), forward * speed)
    err = math.atan2(math.sin(desired - heading), math.cos(desired - heading))
    steer_world = float(np.clip(HEADING_GAIN * err, -0.5, 0.5))
    return -steer_world  # highway-env's heading is mirrored


PURSUIT_LOOKAHEAD_S = 0.6  # [s] pure pursuit looks this far ahead along the path
PURSUIT_MIN_LOOKAHEAD_M = 2.5  # [m]


def _pursuit_steering(v: Vehicle, path) -> float:
    """Steering [rad] (highway-env's sign) of pure pursuit along ``path`` (world frame): the
    curvature 2 sin(alpha) / L_d that meets the path point L_d ahead, turned into the
    bicycle model's steering angle."""
    x, y, heading = v.world_pose()
    ld = max(PURSUIT_LOOKAHEAD_S * abs(v.speed), PURSUIT_MIN_LOOKAHEAD_M)
    tx, ty, _ = path.pose_at(path.closest_s(x, y) + ld)
    alpha = math.atan2(ty - y, tx - x) - heading
    kappa = 2 * math.sin(alpha) / ld
    sin_beta = float(np.clip(kappa * v.LENGTH / 2, -0.5, 0.5))
    delta = math.atan(2 * math.tan(math.asin(sin_beta)))
    return -delta
