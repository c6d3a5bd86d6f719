"""Training scenes seen as the fovea sees them (``bittc generate --fovea-share``).

A fovea scene is a random scene (:mod:`sim.random_scene`) rendered through the fovea of
its jittered camera instead of the wide view: the same optical centre and orientation,
focal x Z, the principal point on the horizon point straight ahead
(``sim.camera.CameraConfig.fovea``). Z is drawn so that the fovea's vertical field of
view is ``FOVEA_VFOV_DEG`` (about zoom 2-6 at the 30 deg default camera), so the views
span what a 2x-6x fovea sees. The sample's images, ground truth and intrinsics are the
fovea's (its ``meta["view"]`` says so); the ground truth comes from the same function
as the wide view's (``sim.stepping.pair_ground_truth``).

What a fovea must fence and what it must not:

- a **target** in or near the ego's lane, 15-150 m ahead: a threat (stationary, slower
  or braking, placed at a bumper TTC drawn log-uniformly in ``FOVEA_TTC_RANGE_S``) or,
  with probability ``FOVEA_BENIGN_SHARE``, a look-alike that closes on no one (a lead at
  the ego's speed or pulling away); overlap 25-100 % of the ego's width on either side
  (Euro NCAP's definition, as ``sim.random_scene``'s braking cases);
- 0-4 **others** at 15-150 m: vehicles in adjacent lanes (slower, faster, at the same
  speed), oncoming vehicles in the lanes left of the ego, another lead in the lane (nearer or
  further than the target, so it may hide it).

Everything is drawn from the scene's one numpy Generator, so the seed fixes the bytes.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from sim.camera import CameraConfig
from sim.scenery import RoadConfig
from sim.vehicles import EGO_SIZE_M

FOVEA_VFOV_DEG = (5.0, 16.0)  # [deg] the fovea's vertical field of view
FOVEA_RANGE_M = (15.0, 150.0)  # [m] gap ahead of the ego's front bumper
FOVEA_TTC_RANGE_S = (0.3, 4.0)  # [s] a threat's bumper TTC at the first frame, log-uniform
FOVEA_EGO_SPEED_MPS = (10 / 3.6, 130 / 3.6)  # [m/s]
FOVEA_THREAT_MOTIONS = ("stationary", "slower", "braking")
FOVEA_BENIGN_MOTIONS = ("same-speed", "receding")
FOVEA_BENIGN_SHARE = 0.5  # share of fovea scenes whose target closes on no one
FOVEA_CLASSES = ("gvt", "car", "van", "truck")
FOVEA_OVERLAP = (0.25, 1.0)  # |share of the ego's width overlapped|, either side
FOVEA_OTHER_MOTIONS = ("adjacent", "adjacent", "oncoming", "lead")
FOVEA_MAX_OTHERS = 4


def fovea_camera(rng: np.random.Generator, camera: CameraConfig) -> CameraConfig:
    """``camera`` (already jittered) with a fovea whose vertical FOV is drawn in ``FOVEA_VFOV_DEG``.

    The per-frame rotation jitter is divided by the zoom: the fovea magnifies a rotation Z
    times, so this keeps the jitter in pixels that of the wide scenes (up to about 1.2 px
    at 0.4 deg and 179 px focal) rather than Z times it."""
    vfov_f = float(rng.uniform(*FOVEA_VFOV_DEG))
    # the fovea's focal is Z times the wide view's, so its FOV is 2 atan(tan(vfov / 2) / Z)
    zoom = max(math.tan(math.radians(camera.vfov_deg) / 2) / math.tan(math.radians(vfov_f) / 2), 1.0)
    # the training fovea spans the full width: the clip is the fovea (sim.camera's narrower
    # closed-loop fovea is a crop of it, and the network is fully convolutional)
    return replace(camera, fovea_zoom=round(zoom, 6), jitter_deg=camera.jitter_deg / zoom, fovea_width_share=1.0)


def _gap_for(rng: np.random.Generator, closing_mps: float) -> float:
    """A gap [m] in ``FOVEA_RANGE_M`` at a TTC drawn log-uniformly in ``FOVEA_TTC_RANGE_S``
    (clipped to the range where the closing speed cannot reach it)."""
    ttc = math.exp(rng.uniform(math.log(FOVEA_TTC_RANGE_S[0]), math.log(FOVEA_TTC_RANGE_S[1])))
    return float(np.clip(ttc * closing_mps, *FOVEA_RANGE_M))


def _log_uniform_gap(rng: np.random.Generator) -> float:
    return float(math.exp(rng.uniform(math.log(FOVEA_RANGE_M[0]), math.log(FOVEA_RANGE_M[1]))))


def threat_motion(rng: np.random.Generator, motion: str, v_ego: float) -> tuple[float, float]:
    """(speed [m/s], acceleration [m/s^2]) of a target ahead that is 'stationary', 'slower'
    (0-80 % of the ego's speed) or 'braking' (from 30-100 % of it at 2-8 m/s^2)."""
    if motion == "stationary":
        return 0.0, 0.0
    if motion == "slower":
        return v_ego * float(rng.uniform(0.0, 0.8)), 0.0
    return v_ego * float(rng.uniform(0.3, 1.0)), -float(rng.uniform(2.0, 8.0))


def fovea_target(rng: np.random.Generator, v_ego: float, length_m: float, width_m: float):
    """(x, y, heading, speed, accel, motion) of the target ahead in or near the ego's lane
    (ego frame at the first frame: x forward to the target's centre, y left) [m, rad, m/s, m/s^2]."""
    accel = 0.0
    if rng.random() < FOVEA_BENIGN_SHARE:
        motion = str(rng.choice(FOVEA_BENIGN_MOTIONS))
        speed = v_ego if motion == "same-speed" else v_ego + float(rng.uniform(1.0, 10.0))
        gap = _log_uniform_gap(rng)
    else:
        motion = str(rng.choice(FOVEA_THREAT_MOTIONS))
        speed, accel = threat_motion(rng, motion, v_ego)
        gap = _gap_for(rng, max(v_ego - speed, 0.5))
    overlap = float(rng.uniform(*FOVEA_OVERLAP)) * float(rng.choice([-1.0, 1.0]))
    y = math.copysign(1.0, overlap) * (1.0 - abs(overlap)) * (EGO_SIZE_M[1] + width_m) / 2
    return EGO_SIZE_M[0] / 2 + gap + length_m / 2, y, 0.0, speed, accel, f"fovea-{motion}"


def fovea_other(rng: np.random.Generator, road: RoadConfig, v_ego: float, length_m: float):
    """(x, y, heading, speed, motion) of another vehicle 15-150 m ahead: in an adjacent lane,
    oncoming in a lane left of the ego, or another lead in the ego's lane (nearer or further than the target)."""
    motion = str(rng.choice(FOVEA_OTHER_MOTIONS))
    x = EGO_SIZE_M[0] / 2 + _log_uniform_gap(rng) + length_m / 2
    heading = 0.0
    if motion == "oncoming" and road.lanes_left > 0:
        lane = int(rng.integers(1, road.lanes_left + 1))
        heading, speed = math.pi, float(rng.uniform(5.0, 30.0))
    elif motion == "lead" or (road.lanes_left == 0 and road.lanes_right == 0):
        motion, lane = "lead", 0
        speed = v_ego + float(rng.uniform(0.0, 8.0))
    else:
        motion = "adjacent"
        lanes = [k for k in (-1, 1) if -road.lanes_right <= k <= road.lanes_left]
        lane = int(rng.choice(lanes))
        speed = max(0.0, v_ego + float(rng.uniform(-10.0, 10.0)))
    y = road.lane_center_y_m(lane) + float(rng.uniform(-0.4, 0.4))
    return x, y, heading, speed, f"fovea-{motion}"
