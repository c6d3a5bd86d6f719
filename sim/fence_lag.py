"""The fence lag of the critical actor: how late each geofence covers it.

Per threshold tau_i: the first job whose map p_i covers at least ``COVER_SHARE`` of the
critical actor's visible pixels (p_i > 0.5) gives the actor's exact camera-plane TTC
tau* then (the median over its pixels of the per-pixel ground truth, from the latest
frame), and the fence's lag tau_i - tau* [s]: 0 for a perfect fence, > 0 when the fence
fires only once the actor is already that much closer than the threshold. The
critical actor is the in-path actor ahead with the smallest bumper-to-bumper TTC at
the job's capture; an actor with fewer than ``MIN_PIXELS`` visible pixels is not
measured in that job.
"""

from __future__ import annotations

import numpy as np

COVER_SHARE = 0.5  # [-] share of the actor's pixels inside the fence
MIN_PIXELS = 4  # [px] fewer visible pixels: too small to measure


class FenceLagMeter:
    def __init__(self) -> None:
        self.cover_ttc_s: dict[float, float] = {}  # threshold [s] -> exact tau* at first cover [s]
        self.thresholds_s: tuple[float, ...] = ()
        self.history: list[tuple[float, dict[str, float]]] = []  # (tau* [s], shares) per measured job

    def update(self, view, gt, critical) -> dict[str, float]:
        """``view``: a ``controllers.base.GeofenceView``; ``gt``: the job frame's
        ``sim.ground_truth.GroundTruth``; ``critical``: its ``ActorTruth``.
        -> '<tau_i>' -> share of the actor's pixels inside fence i (empty when not measured)."""
        self.thresholds_s = tuple(view.thresholds_s)
        pix = (gt.instance == critical.instance) & gt.valid & np.isfinite(gt.tau_s) & (gt.tau_s > 0)
        if int(pix.sum()) < MIN_PIXELS:
            return {}
        tau_star = float(np.median(gt.tau_s[pix]))
        shares = {}
        for tau_i, p in zip(view.thresholds_s, view.maps):
            share = float(np.mean(p[pix] > 0.5))
            shares[f"{tau_i:g}"] = share
            if tau_i not in self.cover_ttc_s and share >= COVER_SHARE:
                self.cover_ttc_s[tau_i] = tau_star
        self.history.append((tau_star, shares))
        return shares

    def lag_s(self) -> dict[str, float | None]:
        """'<tau_i>' -> tau_i - tau* [s], None for a fence that never covered the actor."""
        return {
            f"{t:g}": (round(t - self.cover_ttc_s[t], 4) if t in self.cover_ttc_s else None) for t in self.thresholds_s
        }

    def cover_ttc(self) -> dict[str, float | None]:
        return {f"{t:g}": (round(self.cover_ttc_s[t], 4) if t in self.cover_ttc_s else None) for t in self.thresholds_s}
