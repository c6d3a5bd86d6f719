"""Hand-made estimator maps for the geofence controller's tests: no renderer, no network.

The maps are what a perfect estimator would give at 50 km/h: the road ahead inside every
fence up to its boundary row (``road``), and boxes standing on the road wherever a test
puts them (``add_box``; ``fovea_box`` in the fovea's pixels). ``MapEstimator`` returns its
``tau`` (H, W) camera-plane TTC [s] as hard geofences; ``ViewMapEstimator`` a second map for
frames marked as the fovea's."""

import math

import numpy as np

from controllers.base import Calibration, Observation
from controllers.geofence import GeofenceConfig, GeofenceController
from controllers.road import ground_ttc_per_row
from sim.camera import CameraConfig, cam_T_ego
from sim.vehicles import EGO_SIZE_M

CAM = CameraConfig()
CAL = Calibration.from_camera(CAM, EGO_SIZE_M)
SPEED = 50 / 3.6  # [m/s]
THR = (0.8, 1.2, 1.8, 2.8)  # [s]


class MapEstimator:
    """Returns ``self.tau`` (H, W) camera-plane TTC [s] as hard geofences."""

    dt_s = 0.1
    tau_range_s = (0.2, 10.0)

    def __init__(self):
        self.tau = np.full((CAM.height_px, CAM.width_px), np.inf)

    def geofence(self, prev, latest, thresholds_s):
        t = np.asarray(thresholds_s)[:, None, None]
        return ((self.tau > 0) & (self.tau <= t)).astype(np.float32)


def project(x_fwd_m, y_left_m, z_up_m):
    """Ego-frame point -> (u, v) px."""
    p = cam_T_ego(CAM) @ np.array([x_fwd_m, y_left_m, z_up_m, 1.0])
    fx, fy, cx, cy = CAM.intrinsics()
    return fx * p[0] / p[2] + cx, fy * p[1] / p[2] + cy


def road(speed_mps=SPEED):
    tau = np.repeat(ground_ttc_per_row(CAL, speed_mps)[:, None], CAM.width_px, axis=1)
    return tau


def add_box(tau, dist_m, lateral_m, tau_s, width_m=1.8, height_m=1.5):
    """A vertical face ``dist_m`` ahead of the camera, centred ``lateral_m`` to the left."""
    x = CAM.mount_forward_m + dist_m
    u_a, v_bottom = project(x, lateral_m + width_m / 2, 0.0)
    u_b, v_top = project(x, lateral_m - width_m / 2, height_m)
    u0, u1 = int(math.floor(min(u_a, u_b))), int(math.ceil(max(u_a, u_b)))
    r0, r1 = int(math.floor(v_top)), int(math.ceil(v_bottom))
    tau[max(r0, 0) : max(r1, 0), max(u0, 0) : max(u1, 0)] = tau_s
    return tau


def run(tau_map, speed=SPEED, jobs=3, thresholds=THR, cfg=None):
    est = MapEstimator()
    # maps per pair; ``cfg``: more GeofenceConfig fields
    ctrl = GeofenceController(est, GeofenceConfig(thresholds_s=thresholds, frame_stride=1, **(cfg or {})))
    ctrl.reset(CAL)
    img = np.zeros((CAM.height_px, CAM.width_px, 3), np.uint8)
    est.tau = tau_map
    cmds = [ctrl.act(Observation(0.1 * k, speed, img, img, 0.1, CAL), None) for k in range(jobs)]
    return cmds


def quiet(cmds):
    return all(c.decel_mps2 == 0 and not c.warning for c in cmds)


FOVEA_CAM = CameraConfig(fovea_zoom=4.0)
FOVEA_CAL = Calibration.from_camera(FOVEA_CAM, EGO_SIZE_M)


class ViewMapEstimator(MapEstimator):
    """Hard geofences of ``tau`` for the wide view and ``tau_fovea`` for frames marked as the fovea's."""

    def __init__(self):
        super().__init__()
        self.tau_fovea = np.full_like(self.tau, np.inf)

    def geofence(self, prev, latest, thresholds_s):
        tau = self.tau_fovea if latest[0, 0, 0] == 1 else self.tau
        t = np.asarray(thresholds_s)[:, None, None]
        return ((tau > 0) & (tau <= t)).astype(np.float32)


def fovea_box(dist_m, tau_s, width_m=1.8, height_m=1.5):
    """The road in the fovea's rows with a face standing ``dist_m`` ahead, in fovea pixels."""
    cal = FOVEA_CAL.fovea
    tau = np.repeat(ground_ttc_per_row(cal, SPEED)[:, None], cal.width_px, axis=1)
    pin, T = FOVEA_CAM.fovea(), cam_T_ego(FOVEA_CAM)
    x = FOVEA_CAM.mount_forward_m + dist_m
    (u_a, v_bot), (u_b, v_top) = pin.project(
        np.array([(T @ [x, width_m / 2, 0.0, 1.0])[:3], (T @ [x, -width_m / 2, height_m, 1.0])[:3]])
    )
    tau[int(v_top) : int(math.ceil(v_bot)), int(min(u_a, u_b)) : int(math.ceil(max(u_a, u_b)))] = tau_s
    return tau


def run_two_views(tau_wide, tau_fovea, jobs=3):
    est = ViewMapEstimator()
    est.tau, est.tau_fovea = tau_wide, tau_fovea
    ctrl = GeofenceController(est, GeofenceConfig(thresholds_s=THR, frame_stride=1))
    ctrl.reset(FOVEA_CAL)
    wide = np.zeros((CAM.height_px, CAM.width_px, 3), np.uint8)
    fov = wide.copy()
    fov[0, 0, 0] = 1
    return ctrl, [
        ctrl.act(Observation(0.1 * k, SPEED, wide, wide, 0.1, FOVEA_CAL, fov, fov), None) for k in range(jobs)
    ]
