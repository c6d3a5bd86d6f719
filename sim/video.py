"""Camera video with the exact TTC as a colour overlay and a HUD, written headless."""

from __future__ import annotations

import os
from pathlib import Path

import cv2
import numpy as np

TTC_MAX_S = 4.0  # overlay colours 0 < tau <= TTC_MAX_S [s]; red = imminent


def ttc_overlay(
    image_rgb: np.ndarray,
    tau_s: np.ndarray,
    valid: np.ndarray,
    instance: np.ndarray,
    alpha_actor: float = 0.6,
    alpha_static: float = 0.3,
) -> np.ndarray:
    """Blend a red (0 s) -> yellow -> green (TTC_MAX_S) colour map over approaching pixels;
    vehicles (instance > 0) more strongly than the static world."""
    out = image_rgb.astype(np.float32).copy()
    mask = valid & (tau_s > 0) & (tau_s <= TTC_MAX_S)
    t = np.clip(tau_s / TTC_MAX_S, 0, 1)
    color = np.stack([np.clip(2 - 2 * t, 0, 1), np.clip(2 * t, 0, 1), np.zeros_like(t)], axis=-1) * 255.0
    alpha = np.where(instance > 0, alpha_actor, alpha_static)[..., None]
    out[mask] = (1 - alpha[mask]) * out[mask] + alpha[mask] * color[mask]
    return out.astype(np.uint8)


def threshold_overlay(
    image_rgb: np.ndarray, geofence: np.ndarray, thresholds_s: np.ndarray, alpha: float = 0.5
) -> np.ndarray:
    """Tint each geofence's inside (p > 0.5) from red (shortest tau) to yellow (longest);
    a pixel inside several takes the shortest one's colour (blended once, at ``alpha``)."""
    order = np.argsort(thresholds_s)[::-1]  # longest first, so shorter ones paint over
    k = len(order)
    color = np.zeros(image_rgb.shape, np.float32)
    tinted = np.zeros(image_rgb.shape[:2], bool)
    for rank, i in enumerate(order):
        t = 1.0 - rank / max(k - 1, 1)  # 1 for the longest, 0 for the shortest
        inside = geofence[i] > 0.5
        color[inside] = (255.0, 220.0 * t, 0.0)
        tinted |= inside
    out = image_rgb.astype(np.float32)
    out[tinted] = (1 - alpha) * out[tinted] + alpha * color[tinted]
    return out.round().astype(np.uint8)


def fence_colours(k: int) -> np.ndarray:
    """(K, 3) RGB, the smallest threshold red through yellow to the largest in cyan."""
    t = np.linspace(0.0, 1.0, k) if k > 1 else np.zeros(1)
    return np.stack([np.clip(2 - 2 * t, 0, 1), np.clip(2 * t, 0, 1), np.clip(2 * t - 1, 0, 1)], axis=-1) * 255.0


def geofence_overlay(image_rgb: np.ndarray, view, alpha: float = 0.45) -> np.ndarray:
    """A controller's geofences over its frame: each pixel in the colour of the smallest
    fence it is inside (``fence_colours``), the ego's corridor outlined in white and the
    pixels that counted as in-path evidence in magenta. ``view``: a
    ``controllers.base.GeofenceView`` (thresholds sorted increasing)."""
    out = image_rgb.astype(np.float32).copy()
    colours = fence_colours(len(view.thresholds_s))
    for i in range(len(view.thresholds_s) - 1, -1, -1):  # smaller fences paint over larger ones
        m = view.maps[i] > 0.5
        out[m] = (1 - alpha) * out[m] + alpha * colours[i]
    out[view.counted] = 0.3 * out[view.counted] + 0.7 * np.array([255.0, 0.0, 255.0])
    out = out.astype(np.uint8)
    contours, _ = cv2.findContours(view.corridor.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    cv2.drawContours(out, contours, -1, (255, 255, 255), 1)
    return out


def fovea_inset(wide_scaled: np.ndarray, fovea_rgb: np.ndarray, camera, scale: int) -> np.ndarray:
    """The fovea's image at half the wide view's ``scale`` in the lower right corner of the
    scaled wide image, framed in white, and the fovea's footprint (the wide pixels it
    magnifies, ``camera.fovea_from_wide`` inverted) outlined on the wide view."""
    out = np.ascontiguousarray(wide_scaled).copy()
    wide, fov = camera.wide(), camera.fovea()
    z = camera.fovea_zoom
    # wide pixel of a fovea pixel: u = (u_f - cx_f) / Z + cx, at the fovea's corners (pixel edges)
    u0 = (-0.5 - fov.cx_px) / z + wide.cx_px + 0.5
    u1 = (fov.width_px - 0.5 - fov.cx_px) / z + wide.cx_px + 0.5
    v0 = (-0.5 - fov.cy_px) / z + wide.cy_px + 0.5
    v1 = (fov.height_px - 0.5 - fov.cy_px) / z + wide.cy_px + 0.5
    box = [int(round(x * scale)) for x in (u0, v0, u1, v1)]
    cv2.rectangle(out, (box[0], box[1]), (box[2] - 1, box[3] - 1), (255, 255, 255), 1)
    s = max(1, scale // 2) if scale > 1 else 1
    inset = cv2.resize(fovea_rgb, (fovea_rgb.shape[1] * s, fovea_rgb.shape[0] * s), interpolation=cv2.INTER_NEAREST)
    h, w = inset.shape[:2]
    H, W = out.shape[:2]
    if h + 4 > H or w + 4 > W:
        inset = cv2.resize(inset, (W // 2, H // 2), interpolation=cv2.INTER_AREA)
        h, w = inset.shape[:2]
    out[H - h - 4 : H, W - w - 4 : W] = 255
    out[H - h - 2 : H - 2, W - w - 2 : W - 2] = inset
    label = f"fovea x{z:g}"
    cv2.putText(out, label, (W - w, H - h - 8), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (255, 255, 255), 1, cv2.LINE_AA)
    return out


# one-pixel offsets of the black outline drawn under the white HUD text: a thicker
# stroke would not do, OpenCV widens each glyph's advance with the thickness, so a
# thick outline drifts right of the thin text along the line
_OUTLINE_OFFSETS_PX = [(dx, dy) for dx in (-1, 0, 1) for dy in (-1, 0, 1) if dx or dy]


def hud(image_rgb: np.ndarray, lines: list[str], alert: bool) -> np.ndarray:
    img = np.ascontiguousarray(image_rgb)
    y = 16
    for line in lines:
        for dx, dy in _OUTLINE_OFFSETS_PX:
            cv2.putText(img, line, (6 + dx, y + dy), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (0, 0, 0), 1, cv2.LINE_AA)
        cv2.putText(img, line, (6, y), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (255, 255, 255), 1, cv2.LINE_AA)
        y += 16
    if alert:
        cv2.rectangle(img, (1, 1), (img.shape[1] - 2, img.shape[0] - 2), (255, 0, 0), 3)
    return img


class VideoWriter:
    """mp4 (mp4v) writer that writes to a temporary name and renames on ``close``."""

    def __init__(self, path: str | Path, fps_hz: float, min_width_px: int = 864):
        self.path = Path(path)
        self.tmp = self.path.with_name(f".{self.path.name}.tmp.mp4")
        self.fps = fps_hz
        self.min_width = min_width_px
        self._writer = None

    def scale_for(self, width_px: int) -> int:
        return max(1, int(np.ceil(self.min_width / width_px)))

    def write(self, image_rgb: np.ndarray) -> None:
        if self._writer is None:
            h, w = image_rgb.shape[:2]
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._writer = cv2.VideoWriter(str(self.tmp), cv2.VideoWriter_fourcc(*"mp4v"), self.fps, (w, h))
            if not self._writer.isOpened():
                raise OSError(f"cannot open a video writer for {self.tmp}")
        self._writer.write(cv2.cvtColor(image_rgb, cv2.COLOR_RGB2BGR))

    def close(self) -> None:
        if self._writer is not None:
            self._writer.release()
            os.replace(self.tmp, self.path)
            self._writer = None

    def abort(self) -> None:
        if self._writer is not None:
            self._writer.release()
            self._writer = None
        self.tmp.unlink(missing_ok=True)
