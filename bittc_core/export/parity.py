"""Agreement of two backends on the same pairs: the geofences pixel by pixel (the share
of pixels on the same side of 0.5, per threshold) and the continuous output (|log eta_a -
log eta_b|). ``bittc eval --backend onnxruntime`` reports it against torch."""

from __future__ import annotations

import numpy as np

LOG_ETA_TOLERANCE = 1e-3  # |log eta| difference counted as agreeing


class Agreement:
    def __init__(self, thresholds_s) -> None:
        self.thresholds_s = [float(t) for t in thresholds_s]
        self.same = np.zeros(len(self.thresholds_s))
        self.pixels = 0
        self.log_eta_diffs: list[np.ndarray] = []
        self.pairs = 0

    def add(self, prob_a: np.ndarray, prob_b: np.ndarray, eta_a: np.ndarray, eta_b: np.ndarray) -> None:
        """prob (K, H, W) of the thresholds, eta (H, W) of the two backends on one pair."""
        self.same += ((prob_a > 0.5) == (prob_b > 0.5)).reshape(len(self.thresholds_s), -1).sum(axis=1)
        self.pixels += prob_a[0].size
        self.log_eta_diffs.append(np.abs(np.log(eta_a.astype(np.float64)) - np.log(eta_b.astype(np.float64))).ravel())
        self.pairs += 1

    def result(self) -> dict:
        d = np.concatenate(self.log_eta_diffs) if self.log_eta_diffs else np.zeros(1)
        share = self.same / max(self.pixels, 1)
        return {
            "pairs": self.pairs,
            "geofence_pixels_agreeing": {f"{t:g}": round(float(s), 6) for t, s in zip(self.thresholds_s, share)},
            "geofence_pixels_agreeing_min": round(float(share.min()), 6),
            "log_eta_abs_diff_max": float(d.max()),
            "log_eta_abs_diff_p999": float(np.quantile(d, 0.999)),
            f"log_eta_within_{LOG_ETA_TOLERANCE:g}": round(float((d <= LOG_ETA_TOLERANCE).mean()), 6),
        }
