"""The fovea's smallest fence read on two pairs (``GeofenceConfig.fovea_short_pair``).

The controller pairs frames ``frame_stride`` apart (0.3 s at 10 Hz). A road user crossing
the road moves sideways between them by more than the scale warp about the image centre
aligns (an adult 20 fovea px in 0.3 s), and the network fences it late. On the pair one
frame apart it moves a third as far. So the fovea's smallest fence is read on both pairs
in one call of the estimator (``Estimator.geofence_pairs``: the network classifies each
threshold on its own earlier frame, so the job costs one threshold more), and a pixel is
inside where either reading puts it. The shorter pair is derotated by its own turn
(``Observation.short_pair_rotation_rad``) where the longer one would be; where it turned too far
to use, the fence is read on the longer pair alone.
"""

from __future__ import annotations

import numpy as np

from controllers.base import Calibration, Observation
from controllers.derotate import derotate


def short_frame(obs: Observation, view: str, cal: Calibration, max_rotation_px: float, rotate: bool):
    """-> (the view's frame one interval before the latest, whether it was derotated), or
    None where the observation has none or it turned past ``max_rotation_px`` unrotated."""
    prev = obs.fovea_prev_short if view == "fovea" else None
    if prev is None:
        return None
    turn = obs.short_pair_rotation_rad
    if abs(turn) * cal.fx_px <= max_rotation_px:
        return prev, False
    if not rotate:
        return None
    return derotate(prev, obs.fovea_latest, cal, turn), True


def read_fences(estimator, obs: Observation, view: str, prev, cal: Calibration, cfg, rotate: bool, thr_est, short_thr):
    """-> ((K, H, W) maps of ``thr_est`` (sorted, in the estimator's time base) on (prev,
    the latest frame), the view's tag for the telemetry ``short_pair`` or ""). With
    ``short_thr`` (the smallest fence's threshold on the pair one frame apart, or None) the
    smallest fence is also read on that pair where ``short_frame`` gives it, and the two
    readings are joined by the larger probability."""
    latest = obs.pair(view)[1]
    short = short_frame(obs, view, cal, cfg.max_rotation_px, rotate) if short_thr is not None else None
    if short is None:
        return estimator.geofence(prev, latest, thr_est), ""
    # the longer pair first: the frames are touched in the order the loop's cache model counts
    maps = estimator.geofence_pairs([prev] * len(thr_est) + [short[0]], latest, [*thr_est, short_thr])
    out = maps[:-1].copy()
    out[0] = np.maximum(out[0], maps[-1])
    return out, view + ("-derotated" if short[1] else "")
