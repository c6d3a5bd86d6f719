"""Settings of the geofence controllers (``controllers.geofence``): the thresholds, the
frame stride, the evidence rules and their bounds. Times [s] are camera-plane TTC from
the latest frame unless a name says otherwise."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from bittc_core.errors import ConfigError
from controllers.stages import StageConfig
from controllers.tracker_config import TrackerConfig

DEFAULT_TAU_RANGE_S = (0.8, 2.8)  # [s] camera-plane TTC spanned by default_thresholds
MAX_THRESHOLDS = 64  # thresholds per job: the one bound of K (CLI, sweeps, the controller)
MAX_FRAME_STRIDE = 10  # [frames] the one bound of the frame stride
DEFAULT_FRAME_STRIDE = 3  # [frames] the controller's and the open-loop evaluation's pair stride


def frame_stride_ok(frame_stride) -> bool:
    return (
        not isinstance(frame_stride, bool) and isinstance(frame_stride, int) and 1 <= frame_stride <= MAX_FRAME_STRIDE
    )


def check_frame_stride(frame_stride) -> int:
    """An integer stride in [1, MAX_FRAME_STRIDE]; anything else is refused by value."""
    if not frame_stride_ok(frame_stride):
        raise ConfigError(f"frame stride {frame_stride!r}: must be an integer in [1, {MAX_FRAME_STRIDE}]")
    return frame_stride


#: [s] with a fovea, fences below this run on the wide view only (the 1.5 s fence of K = 1 stays in both)
DEFAULT_FOVEA_FENCES_FROM_S = 1.4


def default_thresholds(num_alphas: int) -> tuple[float, ...]:
    """K thresholds [s], uniform in log tau over DEFAULT_TAU_RANGE_S (K = 1: the geometric mean)."""
    if isinstance(num_alphas, bool) or not isinstance(num_alphas, int) or not 1 <= num_alphas <= MAX_THRESHOLDS:
        raise ConfigError(f"number of thresholds K = {num_alphas!r}: must be an integer in [1, {MAX_THRESHOLDS}]")
    lo, hi = (math.log(t) for t in DEFAULT_TAU_RANGE_S)
    if num_alphas == 1:
        return (round(math.exp((lo + hi) / 2), 4),)
    return tuple(round(math.exp(lo + (hi - lo) * i / (num_alphas - 1)), 4) for i in range(num_alphas))


def check_thresholds(thresholds_s) -> tuple[float, ...]:
    """Finite, > 0, no duplicates, 1..MAX_THRESHOLDS of them; any order."""
    try:
        thr = tuple(float(t) for t in thresholds_s)
    except (TypeError, ValueError):
        raise ConfigError(f"thresholds {thresholds_s!r}: expected a list of numbers [s]") from None
    if not 1 <= len(thr) <= MAX_THRESHOLDS:
        raise ConfigError(f"thresholds {list(thr)}: give 1 to {MAX_THRESHOLDS} values [s]")
    for t in thr:
        if not math.isfinite(t) or t <= 0:
            raise ConfigError(f"threshold {t!r} s: thresholds must be finite and > 0")
    dup = sorted({t for t in thr if thr.count(t) > 1})
    if dup:
        raise ConfigError(f"threshold {dup[0]:g} s is given twice")
    return thr


@dataclass(frozen=True)
class GeofenceConfig:
    thresholds_s: tuple[float, ...] = field(default_factory=lambda: default_thresholds(4))  # [s] camera plane
    stages: StageConfig = field(default_factory=StageConfig)  # bumper-to-bumper TTC stages
    prob_inside: float = 0.5  # [-] a pixel is inside a fence above this probability
    ground_margin: float = 1.25  # [-] count rows with tau_ground > margin * tau_i
    # [rows] only rows more than this many rows above the road's fence edge as the estimator
    # draws it count (the median over the columns; -1, the default: off). For a network that
    # fences the road past its static depth; with the shipped weights it costs a `vru` case, a
    # `benign-vru` false alarm and an early warning (docs/pair_interval.md)
    road_edge_rows: int = -1
    # [-] with the bound on, rows with tau_ground > road_edge_cap * tau_i count regardless
    # (at least ground_margin, checked only when the bound is on)
    road_edge_cap: float = 2.0
    corridor_margin_m: float = 0.25  # [m] beyond the ego's half width, each side
    min_region_px: int = 8  # [px] smallest connected in-path region
    min_face_m2: float = 0.3  # [m^2] smallest face an obstacle shows at the fence's depth
    # [m] smallest height an in-path region spans at the fence's depth, in ``min_height_views``
    # (0: off). The road's own fence edge leaves strips one to five rows tall; 0.3 m at a fence's
    # depth is 4-8 rows in the fovea, one or two in the wide view (there it cost CBLA-25-50)
    min_height_m: float = 0.3
    min_height_views: tuple[str, ...] = ("fovea",)
    contact_px: int = 2  # [px] a region's bottom lies at most this far above the lowest counted row
    nested: bool = True  # a fence's evidence counts only with evidence in a larger fence too
    persistence_frames: int = 2  # [jobs] consecutive jobs before a fence fires
    release_frames: int = 3  # [jobs] without any fence firing before braking is released
    # braking is not released before the contact time that its last firing bounded (the job's
    # time + the fired threshold): a target near enough to fill a view may leave every fence
    # test (its road no longer shows beneath it) while it is still ahead
    hold_to_contact: bool = True
    # the partial stage brakes fully where the view whose fence fired holds a region of
    # oncoming traffic predicted into the path: s / (2 TTC) is what a static obstacle asks,
    # and an oncoming car in a turn across its lane is avoided only by stopping short of it
    oncoming_full: bool = True
    min_speed_mps: float = 1.0  # [m/s] below this: no warning, no braking
    frame_stride: int = DEFAULT_FRAME_STRIDE  # [frames] the pair is (k - stride, k): 3x the motion per pair
    fovea_fences_from_s: float = DEFAULT_FOVEA_FENCES_FROM_S  # [s] with a fovea: fences below run on the wide view only
    tracker: TrackerConfig = field(default_factory=TrackerConfig)  # fenced regions followed over jobs
    # [px] a view whose pair turned further than this (yaw rate x pair interval x focal
    # length; a junction turn: 8 deg in 0.3 s) moves beyond the flow the estimator reads: with
    # ``derotate`` (and a tracker in that view) its earlier frame is warped by the ego's
    # rotation over the pair first (controllers.derotate) and only the tracker's predicted
    # regions count in that job; otherwise the view gives no evidence then
    max_rotation_px: float = 12.0
    derotate: bool = True
    # the fovea's smallest fence is also read on the pair one frame apart (where the
    # observation has it and the stride is longer): a pixel is inside where either pair puts
    # it. A road user crossing moves a third as far sideways there, within what the scale
    # warp about the image centre aligns (controllers.short_pair). Off by default: it costs
    # a threshold a job, and braking 0.01 s later hits two cases harder (docs/vru.md)
    fovea_short_pair: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "thresholds_s", check_thresholds(self.thresholds_s))
        checks = {
            "prob_inside": 0 < self.prob_inside < 1,
            "ground_margin": self.ground_margin >= 1,
            "road_edge_rows": not isinstance(self.road_edge_rows, bool)
            and isinstance(self.road_edge_rows, int)
            and self.road_edge_rows >= -1,
            "road_edge_cap": self.road_edge_rows < 0 or self.road_edge_cap >= self.ground_margin,
            "corridor_margin_m": self.corridor_margin_m >= 0,
            "min_region_px": self.min_region_px >= 1,
            "contact_px": self.contact_px >= 0,
            "min_face_m2": self.min_face_m2 >= 0,
            "min_height_m": self.min_height_m >= 0,
            "min_height_views": all(v in ("wide", "fovea") for v in self.min_height_views),
            "persistence_frames": self.persistence_frames >= 1,
            "release_frames": self.release_frames >= 1,
            "min_speed_mps": self.min_speed_mps >= 0,
            "max_rotation_px": self.max_rotation_px > 0,
            "frame_stride": frame_stride_ok(self.frame_stride),
            "fovea_fences_from_s": math.isfinite(self.fovea_fences_from_s) and self.fovea_fences_from_s >= 0,
        }
        for name, ok in checks.items():
            if not ok:
                raise ConfigError(f"GeofenceConfig.{name} = {getattr(self, name)!r} is out of range")

    def fences(self, views) -> dict[str, np.ndarray]:
        """view -> indices into the sorted thresholds evaluated on it: every fence on the
        wide view, those from ``fovea_fences_from_s`` on on the fovea (at least the largest)."""
        thr = np.sort(np.asarray(self.thresholds_s, dtype=np.float64))
        out = {"wide": np.arange(len(thr))}
        if "fovea" in views:
            out["fovea"] = np.flatnonzero(thr >= min(self.fovea_fences_from_s, thr[-1]) - 1e-9)
        return out


def estimator_thresholds(estimator, thresholds_s, frame_dt_s: float, frame_stride: int = 1) -> np.ndarray:
    """Thresholds [s] for a pair ``frame_stride * frame_dt_s`` apart -> the same
    eta = tau / (tau + pair interval) as thresholds in the estimator's own time base
    (tau * dt_est / pair interval); refused when outside the estimator's trained range."""
    pair_dt_s = frame_dt_s * frame_stride
    thr = np.asarray(thresholds_s, dtype=np.float64)
    thr_est = thr * estimator.dt_s / pair_dt_s
    lo, hi = estimator.tau_range_s
    for t, t_est in zip(thr, thr_est):
        if not lo * (1 - 1e-6) <= t_est <= hi * (1 + 1e-6):
            raise ConfigError(
                f"frame interval {pair_dt_s:g} s ({frame_dt_s:g} s x stride {frame_stride}): threshold {t:g} s asks "
                f"the estimator for {t_est:g} s at its trained {estimator.dt_s:g} s, outside its range "
                f"[{lo:g}, {hi:g}] s"
            )
    return thr_est
