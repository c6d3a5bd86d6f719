"""``flow``: a classical baseline, OpenCV DIS optical flow + local affine expansion.

Convention: DIS is run from the latest to the previous frame, giving f with
latest(x) ~ prev(x + f(x)); our flow (u, v) = -f is the displacement from the
previous to the latest position, in the latest grid (x_prev = x_latest - (u, v)).
A least-squares affine fit of (u, v) over a ``window_px`` square gives the Jacobian
J = d(u, v)/d(x, y); d x_prev / d x_latest = I - J, and since image area scales as
1/Z^2, eta = Z1/Z0 = sqrt|det(I - J)| (optical expansion s = 1/eta). The geofence
is the hard map 1[eta <= eta_i].
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
import torch

from bittc_core.estimator.base import Estimator

DIS_PRESETS = {
    "ultrafast": cv2.DISOPTICAL_FLOW_PRESET_ULTRAFAST,
    "fast": cv2.DISOPTICAL_FLOW_PRESET_FAST,
    "medium": cv2.DISOPTICAL_FLOW_PRESET_MEDIUM,
}


@dataclass(frozen=True)
class FlowBaselineConfig:
    preset: str = "medium"
    window_px: int = 9  # side of the square over which the affine map is fitted
    dt_s: float = 0.1  # [s] frame interval
    tau_min_s: float = 1e-3  # [s] accepted geofence thresholds (any positive value)
    tau_max_s: float = 1e6


def _to_gray_u8(image: torch.Tensor) -> np.ndarray:
    rgb = (image[0].permute(1, 2, 0).numpy() * 255.0 + 0.5).astype(np.uint8)
    return cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY)


def affine_eta(flow_px: np.ndarray, window_px: int) -> np.ndarray:
    """(H, W, 2) flow (u, v) [px] in the latest grid -> (H, W) float32 eta."""
    h, w = flow_px.shape[:2]
    ys, xs = np.mgrid[0:h, 0:w].astype(np.float32)
    k = (window_px, window_px)

    def box(a: np.ndarray) -> np.ndarray:
        return cv2.boxFilter(a, -1, k, normalize=True, borderType=cv2.BORDER_REFLECT_101)

    mx, my = box(xs), box(ys)
    var_x = np.maximum(box(xs * xs) - mx * mx, 1e-6)
    var_y = np.maximum(box(ys * ys) - my * my, 1e-6)
    u, v = flow_px[..., 0], flow_px[..., 1]
    mu, mv = box(u), box(v)
    # x and y are uncorrelated over a product window, so the slopes separate
    du_dx = (box(u * xs) - mu * mx) / var_x
    du_dy = (box(u * ys) - mu * my) / var_y
    dv_dx = (box(v * xs) - mv * mx) / var_x
    dv_dy = (box(v * ys) - mv * my) / var_y
    det = (1.0 - du_dx) * (1.0 - dv_dy) - du_dy * dv_dx
    return np.sqrt(np.abs(det)).astype(np.float32)


class FlowEstimator(Estimator):
    name = "flow"

    def __init__(self, config: FlowBaselineConfig = FlowBaselineConfig()) -> None:
        if config.preset not in DIS_PRESETS:
            raise ValueError(f"DIS preset {config.preset!r}: expected one of {sorted(DIS_PRESETS)}")
        super().__init__(dt_s=config.dt_s, tau_range_s=(config.tau_min_s, config.tau_max_s))
        self.config = config
        self._dis = cv2.DISOpticalFlow_create(DIS_PRESETS[config.preset])
        self._last: tuple[torch.Tensor, torch.Tensor, np.ndarray] | None = None  # pair -> eta

    def fork(self) -> FlowEstimator:
        """Another flow estimator with the same settings and nothing remembered (one per camera view)."""
        return FlowEstimator(self.config)

    def flow(self, prev: torch.Tensor, latest: torch.Tensor) -> np.ndarray:
        """(H, W, 2) float32 flow (u, v) [px], previous -> latest, in the latest grid."""
        f = self._dis.calc(_to_gray_u8(latest), _to_gray_u8(prev), None)
        return -f

    def _motion_in_depth(self, prev: torch.Tensor, latest: torch.Tensor) -> np.ndarray:
        """eta map; the last pair's result is reused when the same pixels come again."""
        if self._last is not None and torch.equal(self._last[0], prev) and torch.equal(self._last[1], latest):
            return self._last[2].copy()
        eta = affine_eta(self.flow(prev, latest), self.config.window_px)
        self._last = (prev.clone(), latest.clone(), eta)
        return eta.copy()

    def _geofence(self, prev: torch.Tensor, latest: torch.Tensor, eta: np.ndarray) -> np.ndarray:
        eta_map = self._motion_in_depth(prev, latest)
        return (eta_map[None] <= eta.astype(np.float32)[:, None, None]).astype(np.float32)
