"""The controller interface: what a braking policy sees and what it returns.

A controller is built once with its settings and reset at the start of every run with
the car's calibration (:class:`Calibration`). The closed loop (``sim.loop``) calls
``act`` once per estimator job: on the frame the latency schedule hands it, not
necessarily on every frame. A deployable controller observes only what a car has
(:class:`Observation`): the two latest frames of its pair, its own speed and the
calibration. Ground truth (:class:`sim.episode.StepTruth`) is passed only to
controllers that declare ``uses_ground_truth`` (the oracle: the upper bound).

Latency is not the policy's business: the loop charges the job's latency (measured,
fixed or from a device profile, see ``sim.latency``) and applies the command when the
output is ready; the brake actuator's delay comes after that.

Writing one (``--controller my_file.py:MyController`` or ``my_module:MyController``
loads it; see ``examples/my_controller.py``)::

    class MyController(Controller):
        name = "mine"
        needs_camera = True          # the loop renders frames and pairs them
        estimator_kind = "flow"      # what a device profile charges per job ("bittc" or "flow")
        num_alphas = 1               # thresholds per job and view

        def reset(self, calibration):
            self.cal = calibration

        def act(self, obs, truth):
            ...                      # obs.image_prev, obs.image_latest, obs.ego_speed_mps
            return BrakeCommand(decel_mps2=0.0, warning=False)
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass(frozen=True)
class Calibration:
    """What the car knows about its own camera and body.

    Convention: pinhole camera, pixel centres at integer (u, v) = (column, row); the
    camera looks along the ego's x axis, pitched down by ``pitch_deg``, its optical
    centre ``mount_height_m`` above the ground and ``mount_forward_m`` ahead of the
    centre of the ego's footprint. Camera-plane TTC (the estimator's) counts to the
    plane through the optical centre; the front bumper lies ``bumper_ahead_m`` ahead.

    ``fovea``: the calibration of the camera's second, magnified view (same optical
    centre, mount and pitch; focal x zoom, principal point on the horizon point straight
    ahead), or None for a camera with one view.
    """

    width_px: int
    height_px: int
    fx_px: float
    fy_px: float
    cx_px: float
    cy_px: float
    mount_height_m: float  # [m] optical centre above the ground
    mount_forward_m: float  # [m] optical centre ahead of the footprint centre
    pitch_deg: float  # [deg] positive looks down
    frame_dt_s: float  # [s] camera frame interval
    ego_length_m: float  # [m] the ego's footprint
    ego_width_m: float  # [m]
    fovea: Calibration | None = None  # the magnified view of the same camera, if any

    @property
    def bumper_ahead_m(self) -> float:
        """[m] front bumper ahead of the camera plane (along the ego's x axis)."""
        return self.ego_length_m / 2 - self.mount_forward_m

    @property
    def views(self) -> dict[str, Calibration]:
        """'wide' -> this view (without its fovea), and 'fovea' -> the fovea where there is one."""
        from dataclasses import replace

        out = {"wide": replace(self, fovea=None)}
        if self.fovea is not None:
            out["fovea"] = self.fovea
        return out

    @classmethod
    def from_camera(cls, camera, ego_size_m: tuple[float, ...]) -> Calibration:
        """From a ``sim.camera.CameraConfig`` (both of its views) and the ego's
        (length, width[, height]) [m]."""

        def one(view, fovea=None) -> Calibration:
            return cls(
                view.width_px,
                view.height_px,
                float(view.fx_px),
                float(view.fy_px),
                float(view.cx_px),
                float(view.cy_px),
                camera.mount_height_m,
                camera.mount_forward_m,
                camera.pitch_deg,
                camera.dt_s,
                float(ego_size_m[0]),
                float(ego_size_m[1]),
                fovea,
            )

        fovea = camera.fovea()
        return one(camera.wide(), one(fovea) if fovea is not None else None)


@dataclass(frozen=True)
class Observation:
    """What a deployable controller sees in one job: the pair, its own speed and yaw rate
    (what a car's wheel-speed and yaw-rate sensors give) and its calibration. With a fovea
    (``calibration.fovea``), ``fovea_latest`` / ``fovea_prev`` are the same two captures
    through the magnified view."""

    t_s: float  # capture time of the latest frame [s]
    ego_speed_mps: float  # the ego's speed at that capture [m/s]
    image_latest: np.ndarray | None  # (H, W, 3) uint8 RGB; None when the controller needs no camera
    image_prev: np.ndarray | None  # the frame captured frame_stride frames before, same format
    dt_s: float  # [s] time between the two frames of the pair
    calibration: Calibration | None = None
    fovea_latest: np.ndarray | None = None  # (H, W, 3) uint8 RGB through the fovea; None without one
    fovea_prev: np.ndarray | None = None
    ego_yaw_rate_radps: float = 0.0  # [rad/s] + turning left, from the car's yaw-rate sensor at the capture
    # [rad] + left: the ego's heading change from the earlier capture of the pair to the latest
    # (what its yaw-rate sensor integrates to; the simulator gives the exact change); None
    # where unknown (then yaw rate x dt_s)
    pair_yaw_rad: float | None = None
    # the fovea's capture one frame interval before the latest, where the pair is longer
    # (``GeofenceConfig.fovea_short_pair``), and the ego's heading change over that interval
    # [rad] (+ left); None where there is none
    fovea_prev_short: np.ndarray | None = None
    short_pair_yaw_rad: float | None = None

    def pair(self, view: str) -> tuple[np.ndarray | None, np.ndarray | None]:
        """(prev, latest) images of view 'wide' or 'fovea'."""
        return (self.image_prev, self.image_latest) if view == "wide" else (self.fovea_prev, self.fovea_latest)

    @property
    def pair_rotation_rad(self) -> float:
        """[rad] + left: the ego's heading change over the pair (``pair_yaw_rad``, else the
        yaw rate at the capture times the pair's interval)."""
        return float(self.pair_yaw_rad) if self.pair_yaw_rad is not None else float(self.ego_yaw_rate_radps) * self.dt_s

    @property
    def short_pair_rotation_rad(self) -> float:
        """[rad] + left: the ego's heading change over the shorter pair, one frame interval
        (``short_pair_yaw_rad``, else the yaw rate times the calibration's frame interval)."""
        if self.short_pair_yaw_rad is not None:
            return float(self.short_pair_yaw_rad)
        return float(self.ego_yaw_rate_radps) * self.calibration.frame_dt_s


@dataclass(frozen=True)
class GeofenceView:
    """What a geofence controller saw in one job through one camera view, for videos and
    fence-lag measurement.

    ``maps``: (K, H, W) float32 p(0 < tau <= thresholds_s[i]) of the latest frame;
    ``counted``: (H, W) bool, the in-path regions that counted as evidence for any fence;
    ``corridor``: (H, W) bool, the ego's corridor for the largest fence."""

    thresholds_s: tuple[float, ...]  # [s] camera-plane TTC, from the latest frame
    maps: np.ndarray
    counted: np.ndarray
    corridor: np.ndarray


@dataclass(frozen=True)
class BrakeCommand:
    decel_mps2: float = 0.0  # requested deceleration [m/s^2], >= 0
    warning: bool = False  # forward-collision warning on
    telemetry: Mapping[str, Any] = field(default_factory=dict, compare=False)  # scalars for trace.csv
    view: GeofenceView | None = field(default=None, compare=False)  # maps behind the decision, if any
    fovea_view: GeofenceView | None = field(default=None, compare=False)  # the same through the fovea

    def views(self) -> dict[str, GeofenceView]:
        """'wide' / 'fovea' -> the maps behind the decision in that view (those that exist)."""
        return {k: v for k, v in (("wide", self.view), ("fovea", self.fovea_view)) if v is not None}

    def check(self, who: str) -> None:
        """Refuse a command that is not a deceleration [m/s^2] >= 0."""
        d = self.decel_mps2
        if isinstance(d, bool) or not isinstance(d, (int, float, np.floating)) or not math.isfinite(d) or d < 0:
            raise ValueError(f"controller {who!r} returned decel_mps2 = {d!r}: must be a finite number >= 0")


class Controller(ABC):
    """Observation (+ truth for oracles) -> brake command."""

    name: str = "controller"
    needs_camera: bool = False  # the loop renders frames and hands over pairs
    uses_ground_truth: bool = False  # oracles only
    # oracles only: the loop adds each view's per-pixel ground truth to ``truth.pixels``
    uses_pixel_truth: bool = False
    num_alphas: int = 0  # thresholds evaluated per job and view (the K a latency profile charges)
    frame_stride: int = 1  # the pair is (frame k - frame_stride, frame k)
    # what a device profile charges per job (sim.latency): the estimator family, None for none;
    # the camera views it runs on (set by ``reset`` from the calibration); its feature cache [frames]
    estimator_kind: str | None = None
    views: tuple[str, ...] = ("wide",)
    cached_frames: int = 0

    @property
    def view_thresholds(self) -> dict[str, int]:
        """View -> thresholds evaluated on it per job (``num_alphas`` on each by default)."""
        return {v: self.num_alphas for v in self.views}

    @property
    def job_thresholds(self) -> int:
        """Thresholds evaluated per job, summed over the views."""
        return sum(self.view_thresholds.values())

    def reset(self, calibration: Calibration) -> None:  # noqa: B027 (an optional hook)
        """Forget any state from a previous run; ``calibration`` is this run's car."""

    @abstractmethod
    def act(self, obs: Observation, truth) -> BrakeCommand:
        """Decide from the latest observation. ``truth`` is for oracles only (else None)."""
