"""Taking the ego's own rotation out of a frame pair before the estimator sees it.

In a junction turn the ego yaws by 8 deg within a 0.3 s pair (20 km/h on a 12 m radius):
every pixel of the wide view moves 25 px sideways, the fovea's 100 px, far beyond the
motion the network was trained on, and it fences the road ahead. The car knows that
rotation: its yaw-rate sensor, integrated over the pair
(``controllers.base.Observation.pair_yaw_rad``). A pure rotation of a camera about its
optical centre moves every pixel by the homography H = K R K^-1, whatever the depth, so
the earlier frame is warped into the orientation of the latest one. What is left is the
parallax of the ego's translation, which carries the time to contact.

Convention: OpenCV camera frame (x right, y down, z forward), pitched down by p about
its x axis; the ego's up axis is then (0, -cos p, -sin p) in the camera frame. A yaw of
psi [rad] (+ left) turns a static bearing d seen before into R(up, -psi) d after: left
turns move the scene to the right in the image. The camera-plane TTC of the derotated
pair is that of the translation alone, Z / (s cos p) for the static ground
(``controllers.evidence.ground_ttc_map`` with no yaw rate).

Pixels of the latest frame that the earlier frame did not see (a strip on the side the
ego turns towards) take the latest frame's own values: no motion, so no fence.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from controllers.base import Calibration


def rotation_homography(cal: Calibration, yaw_rad: float) -> np.ndarray:
    """(3, 3) H: a pixel (u, v, 1) of a frame taken ``yaw_rad`` [rad] (+ left) of the ego's
    heading before the latest one -> where that bearing lies in the latest frame."""
    p = math.radians(cal.pitch_deg)
    up = np.array([0.0, -math.cos(p), -math.sin(p)])
    R, _ = cv2.Rodrigues(up * -float(yaw_rad))
    K = np.array([[cal.fx_px, 0.0, cal.cx_px], [0.0, cal.fy_px, cal.cy_px], [0.0, 0.0, 1.0]])
    return K @ R @ np.linalg.inv(K)


def derotate(prev: np.ndarray, latest: np.ndarray, cal: Calibration, yaw_rad: float) -> np.ndarray:
    """The earlier (H, W, 3) uint8 frame ``prev`` of a pair seen in the latest frame's
    orientation: the ego turned by ``yaw_rad`` [rad] (+ left) between the two captures.
    Where ``prev`` saw nothing, ``latest``'s pixels. ``prev`` itself at no rotation."""
    if yaw_rad == 0.0:
        return prev
    h, w = prev.shape[:2]
    H = rotation_homography(cal, yaw_rad)
    warped = cv2.warpPerspective(prev, H, (w, h), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    seen = cv2.warpPerspective(np.ones((h, w), np.uint8), H, (w, h), flags=cv2.INTER_NEAREST, borderValue=0)
    return np.where(seen[..., None].astype(bool), warped, latest)
