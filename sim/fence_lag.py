"""The fence lag of the critical actor: how late each geofence covers it, per camera view.

Per threshold tau_i and view (wide, fovea): the first job whose map p_i covers at least
``COVER_SHARE`` of the critical actor's visible pixels in that view (p_i > the
controller's ``prob_inside``) gives the actor's exact camera-plane TTC tau* then (the
median over its pixels of the per-pixel ground truth, from the latest frame), and the
fence's lag tau_i - tau* [s]. The lag without a view (``fence_lag_s``) is that of the
earlier cover of the views. The persistent lag (``fence_lag_persistent_s``) takes the
first job from which the fence covers at least half of the actor in every later
measured job while the actor is still to come inside the fence or inside it (up to the
last job at which its exact tau* <= tau_i: contact in an open-loop run, the moment
braking takes it back out of the fence in a closed one), in one view or the other: one
early frame of flicker does not count.

Resolution: jobs happen at discrete frames, so a perfect fence, on from the instant
tau* = tau_i, shows a lag between 0 and one job interval (the time between jobs: the
frame interval, or more when the estimator is busy). Lags are > 0 when the fence fires
only once the actor is that much closer than the threshold, < 0 when it fires early.

The critical actor is the in-path actor ahead with the smallest bumper-to-bumper TTC at
the job's capture; an actor with fewer than ``MIN_PIXELS`` visible pixels in a view is
not measured in that view in that job. The first job that measures it in any view gives
the TTC at which the camera first saw it (``first_seen_ttc_s``, bumper to bumper like the
warning's): a crossing car on a collision course stays at a constant bearing, which may lie
outside the camera's field of view until the last second.
"""

from __future__ import annotations

import numpy as np

COVER_SHARE = 0.5  # [-] share of the actor's pixels inside the fence
MIN_PIXELS = 4  # [px] fewer visible pixels: too small to measure


class FenceLagMeter:
    """Args: prob_inside: a pixel is inside a fence above this probability (the controller's)."""

    def __init__(self, prob_inside: float = 0.5) -> None:
        self.prob_inside = float(prob_inside)
        self.thresholds_s: tuple[float, ...] = ()
        self.cover_ttc_s: dict[str, dict[float, float]] = {}  # view -> threshold [s] -> tau* at first cover [s]
        # (tau* [s], '<tau_i>' -> share inside in the view that covers most) per measured job
        self.history: list[tuple[float, dict[str, float]]] = []
        # [s] the critical actor's bumper-to-bumper TTC at the first job that saw it in any view
        self.first_seen_ttc_s: float | None = None

    def update(self, views: dict, gts: dict, critical) -> dict[str, dict[str, float]]:
        """``views``: view name -> ``controllers.base.GeofenceView``; ``gts``: view name -> the
        job frame's ``sim.ground_truth.GroundTruth`` in that view; ``critical``: its ``ActorTruth``.
        -> view -> '<tau_i>' -> share of the actor's pixels inside fence i (views not measured left out)."""
        out: dict[str, dict[str, float]] = {}
        tau_star = None
        for name, view in views.items():
            gt = gts.get(name)
            if gt is None:
                continue
            self.thresholds_s = tuple(sorted(set(self.thresholds_s) | set(view.thresholds_s)))  # views may differ
            pix = (gt.instance == critical.instance) & gt.valid & np.isfinite(gt.tau_s) & (gt.tau_s > 0)
            if int(pix.sum()) < MIN_PIXELS:
                continue
            if self.first_seen_ttc_s is None:
                self.first_seen_ttc_s = float(critical.ttc_s)
            tau_v = float(np.median(gt.tau_s[pix]))
            tau_star = tau_v if tau_star is None else tau_star
            shares = {}
            covers = self.cover_ttc_s.setdefault(name, {})
            for tau_i, p in zip(view.thresholds_s, view.maps):
                share = float(np.mean(p[pix] > self.prob_inside))
                shares[f"{tau_i:g}"] = share
                if tau_i not in covers and share >= COVER_SHARE:
                    covers[tau_i] = tau_v
            out[name] = shares
        if tau_star is not None:
            keys = sorted({k for sh in out.values() for k in sh}, key=float)
            best = {k: max(sh[k] for sh in out.values() if k in sh) for k in keys}
            self.history.append((tau_star, best))
        return out

    def cover_ttc(self, view: str | None = None) -> dict[str, float | None]:
        """'<tau_i>' -> tau* [s] at the first cover in ``view`` (None: the earlier of the views)."""
        out = {}
        for t in self.thresholds_s:
            hits = [c[t] for v, c in self.cover_ttc_s.items() if (view is None or v == view) and t in c]
            out[f"{t:g}"] = round(max(hits), 4) if hits else None
        return out

    def lag_s(self, view: str | None = None) -> dict[str, float | None]:
        """'<tau_i>' -> tau_i - tau* [s] at the first cover, None for a fence that never covered the actor."""
        return {k: (round(float(k) - c, 4) if c is not None else None) for k, c in self.cover_ttc(view).items()}

    def persistent_lag_s(self) -> dict[str, float | None]:
        """'<tau_i>' -> tau_i - tau* [s] at the first measured job from which the fence covers
        half of the actor in every later measured job up to the last one with tau* <= tau_i;
        None when it never holds that long (or the actor never came inside)."""
        out = {}
        for t in self.thresholds_s:
            k = f"{t:g}"
            inside = [j for j, (tau, _) in enumerate(self.history) if tau <= t]
            start = None
            for tau, shares in self.history[: inside[-1] + 1] if inside else []:
                if shares.get(k, 0.0) >= COVER_SHARE:
                    start = tau if start is None else start
                else:
                    start = None
            out[k] = round(t - start, 4) if start is not None else None
        return out
