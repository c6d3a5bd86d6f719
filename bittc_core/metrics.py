"""Evaluation metrics of binary and continuous TTC (numpy, one image at a time).

Conventions: maps are (H, W) in the latest grid; ``valid`` marks pixels with exact
ground truth; geofence class of a pixel for tau_i: inside = eta <= eta_i (with eta > 0),
eta_i = tau_i / (tau_i + dt_s).

* miou: BiTTC Table 1 protocol: for ``MIOU_LEVELS`` thresholds spaced uniformly in eta
  for tau in [0.2 s, 2 s], the IoU of the inside class and of the outside class over
  valid pixels, averaged over the two classes (a class absent from both prediction and
  truth is skipped), then over thresholds and images.
* mid: mean |log eta_hat - log eta| * 1e4 over valid pixels with |log eta| < log 2,
  pooled over all such pixels of the data set.
* error_rate: per threshold tau in ``ERROR_RATE_TAUS_S``, the share of valid pixels whose
  class is wrong, pooled over the data set; keyed by f"{tau:g}" ("1", "2", "5").
* actor_iou: like miou but only over valid pixels of vehicles (actors, instance > 0),
  moving or not, at tau = 1 and 2 s, with intersections and unions pooled over the data
  set (actors are often absent from an image) and averaged over the two classes.
* class_iou: the actor IoU per actor class (car, pedestrian, cyclist) when ``add`` gets
  the class map (``bittc_core.data.dataset.class_map``).
* breakdown (where the errors are): the mIoU per threshold; the (image, threshold)
  pairs of the mIoU grouped by the share of valid pixels inside the geofence
  (``INSIDE_SHARE_EDGES``), with their mean two-class IoU and their mean inside-class IoU
  over the pairs where truth or prediction has inside pixels (``pairs_with_inside_union``;
  in group "0" those are the pairs with false inside pixels, each scoring 0); the MiD of
  actor pixels and of static pixels apart; when ``add`` gets the ego speed, the images
  grouped by it (``EGO_SPEED_EDGES_MPS``) with their mIoU and the error of their static
  pixels at tau = 1 s split into false inside and missed (a standing ego's static world
  has tau = inf, a moving one's ground tau = Z / v_ego); the errors of the mIoU maps by
  the pixel's margin to the threshold, m = |log eta - log eta_i| (``MARGIN_EDGES``: the
  share of all errors in each margin group and the error rate there), and the mIoU the
  same maps would score if every error within a margin ``FORGIVEN_MARGINS`` were right
  (how much of the loss a more precise reading of eta near the threshold can win back).
  Thresholds are keyed by ``threshold_key``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from bittc_core.ttc import eta_to_tau, tau_to_eta

#: actor classes of the ground truth: id -> name (0: the static world and the sky)
ACTOR_CLASSES = {1: "car", 2: "pedestrian", 3: "cyclist"}

MIOU_TAU_RANGE_S = (0.2, 2.0)
MIOU_LEVELS = 10
ERROR_RATE_TAUS_S = (1.0, 2.0, 5.0)
ACTOR_TAUS_S = (1.0, 2.0)
MID_MAX_LOG_ETA = float(np.log(2.0))
MID_SCALE = 1e4
INSIDE_SHARE_EDGES = (0.05, 0.2)  # inside-share groups: 0, (0, 5 %), [5, 20 %), [20, 100 %]
INSIDE_SHARE_LABELS = ("0", "0-5%", "5-20%", "20-100%")
EGO_SPEED_EDGES_MPS = (0.5, 5.0, 15.0)  # [m/s] ego-speed groups of the breakdown
EGO_SPEED_LABELS = ("<0.5", "0.5-5", "5-15", ">=15")
STATIC_ERROR_TAU_S = 1.0  # [s] threshold of the static-pixel error by ego speed (one of ERROR_RATE_TAUS_S)
MARGIN_EDGES = (0.005, 0.01, 0.02, 0.04, 0.08, 0.16)  # [log eta] margin groups of the breakdown
FORGIVEN_MARGINS = (0.01, 0.02, 0.04)  # [log eta] margins of the breakdown's forgiving mIoU


def miou_thresholds_s(dt_s: float, levels: int = MIOU_LEVELS) -> np.ndarray:
    """Thresholds [s] spanning MIOU_TAU_RANGE_S uniformly in eta."""
    lo, hi = (tau_to_eta(t, dt_s) for t in MIOU_TAU_RANGE_S)
    return eta_to_tau(np.linspace(lo, hi, levels), dt_s)


def inside_geofence(eta: np.ndarray, eta_i: float) -> np.ndarray:
    """Ground-truth class: 0 < tau <= tau_i <=> 0 < eta <= eta_i."""
    with np.errstate(invalid="ignore"):
        return (eta > 0) & (eta <= eta_i)


def class_counts(pred: np.ndarray, truth: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """(2, 2) [[intersection, union] of inside, [..] of outside] over ``mask``."""
    p, t = pred[mask], truth[mask]
    return np.array([[np.sum(p & t), np.sum(p | t)], [np.sum(~p & ~t), np.sum(~p | ~t)]], dtype=np.int64)


def two_class_iou(counts: np.ndarray) -> float:
    """Mean IoU of the classes with a non-empty union; nan if none."""
    ious = [i / u for i, u in counts if u > 0]
    return float(np.mean(ious)) if ious else float("nan")


def threshold_key(tau_s: float) -> str:
    """The JSON key (and listed value) of a threshold [s]: 4 decimals, trailing zeros cut."""
    return f"{round(float(tau_s), 4):g}"


def inside_share_group(inside_px: int, valid_px: int) -> str:
    """Label of the inside-share group of one (image, threshold) pair."""
    if inside_px == 0:
        return INSIDE_SHARE_LABELS[0]
    share = inside_px / max(valid_px, 1)
    return INSIDE_SHARE_LABELS[1 + int(np.searchsorted(INSIDE_SHARE_EDGES, share, side="right"))]


def image_miou(ious: list[float]) -> float | None:
    """An image's mIoU: the mean over its thresholds with a finite IoU; None if none."""
    finite = [x for x in ious if np.isfinite(x)]
    return float(np.mean(finite)) if finite else None


def margin_labels() -> list[str]:
    """Labels of the margin groups: "<0.005", "0.005-0.01", ..., ">=0.16"."""
    e = MARGIN_EDGES
    return [f"<{e[0]:g}", *(f"{a:g}-{b:g}" for a, b in zip(e[:-1], e[1:])), f">={e[-1]:g}"]


def mid_terms(eta_hat: np.ndarray, eta: np.ndarray, valid: np.ndarray) -> tuple[float, int]:
    """(sum of |log eta_hat - log eta|, pixel count) over the MiD pixels."""
    with np.errstate(divide="ignore", invalid="ignore"):
        log_eta = np.log(eta)
        mask = valid & np.isfinite(log_eta) & (np.abs(log_eta) < MID_MAX_LOG_ETA)
        err = np.abs(np.log(np.maximum(eta_hat[mask], 1e-6)) - log_eta[mask])
    return float(err.sum()), int(mask.sum())


@dataclass
class MetricAccumulator:
    """Feed one image at a time with ``add``; ``result()`` gives the JSON-ready dict."""

    dt_s: float
    miou_thresholds_s: np.ndarray = field(init=False)
    _errors: dict = field(default_factory=dict)
    _actor: dict = field(default_factory=dict)
    _class: dict = field(default_factory=dict)  # class name -> tau -> (2, 2) counts
    _latency_ms: list = field(default_factory=list)
    _iou_by_threshold: list = field(default_factory=list)  # per image: MIOU_LEVELS ious (nan: skipped)
    _by_share: dict = field(default_factory=dict)  # label -> [[two-class iou], [inside iou], [false inside px]]
    _mid_parts: dict = field(default_factory=dict)  # "actor" / "static" -> [sum, count]
    _by_speed: dict = field(default_factory=dict)  # label -> [[image miou], [false inside, missed, static px]]
    _margin: np.ndarray = field(init=False)  # (2, groups): errors, pixels of the mIoU maps by margin
    _forgiven: list = field(default_factory=list)  # per image: (FORGIVEN_MARGINS, MIOU_LEVELS) ious

    def __post_init__(self) -> None:
        self.miou_thresholds_s = miou_thresholds_s(self.dt_s)
        self._by_share = {label: [[], [], []] for label in INSIDE_SHARE_LABELS}
        self._mid_parts = {"actor": [0.0, 0], "static": [0.0, 0]}
        self._errors = {t: [0, 0] for t in ERROR_RATE_TAUS_S}
        self._actor = {t: np.zeros((2, 2), np.int64) for t in ACTOR_TAUS_S}
        self._by_speed = {label: [[], np.zeros(3, np.int64)] for label in EGO_SPEED_LABELS}
        self._margin = np.zeros((2, len(MARGIN_EDGES) + 1), np.int64)

    @property
    def thresholds_s(self) -> np.ndarray:
        """All thresholds [s] whose geofence maps ``add`` expects, in this order."""
        return np.concatenate([self.miou_thresholds_s, ERROR_RATE_TAUS_S])

    def add(
        self,
        prob: np.ndarray,
        eta_hat: np.ndarray | None,
        eta: np.ndarray,
        valid: np.ndarray,
        instance: np.ndarray,
        latency_ms: float | None = None,
        ego_speed_mps: float | None = None,
        classes: np.ndarray | None = None,
    ) -> None:
        """prob: (K, H, W) geofence probabilities for ``thresholds_s``; eta_hat: (H, W) or None;
        ego_speed_mps: the ego's speed at the latest frame [m/s], None where unknown."""
        if prob.shape[0] != len(self.thresholds_s):
            raise ValueError(f"expected {len(self.thresholds_s)} maps, got {prob.shape[0]}")
        pred = prob > 0.5
        n = len(self.miou_thresholds_s)
        valid_px = int(valid.sum())
        ious = []
        forgiven = np.full((len(FORGIVEN_MARGINS), n), np.nan)
        with np.errstate(divide="ignore", invalid="ignore"):
            log_eta = np.log(eta)
        for i, t in enumerate(self.miou_thresholds_s):
            eta_i = tau_to_eta(t, self.dt_s)
            truth = inside_geofence(eta, eta_i)
            counts = class_counts(pred[i], truth, valid)
            ious.append(two_class_iou(counts))
            # eta <= 0 (behind the camera) or nan: never near a threshold, margin inf
            margin = np.where(np.isfinite(log_eta), np.abs(log_eta - np.log(eta_i)), np.inf)
            wrong = (pred[i] != truth) & valid
            margin_group = np.searchsorted(MARGIN_EDGES, margin, side="right")
            self._margin[0] += np.bincount(margin_group[wrong], minlength=len(MARGIN_EDGES) + 1)
            self._margin[1] += np.bincount(margin_group[valid], minlength=len(MARGIN_EDGES) + 1)
            for j, m in enumerate(FORGIVEN_MARGINS):
                forgiven[j, i] = two_class_iou(class_counts(np.where(margin < m, truth, pred[i]), truth, valid))
            if np.isfinite(ious[-1]):
                inside_px = int(np.sum(truth & valid))
                group = self._by_share[inside_share_group(inside_px, valid_px)]
                group[0].append(ious[-1])
                if counts[0, 1] > 0:
                    group[1].append(counts[0, 0] / counts[0, 1])
                    group[2].append(int(counts[0, 1]) - inside_px)  # union minus truth: false inside
        self._iou_by_threshold.append(ious)
        self._forgiven.append(forgiven)
        actors = valid & (instance > 0)
        for j, t in enumerate(ERROR_RATE_TAUS_S):
            truth = inside_geofence(eta, tau_to_eta(t, self.dt_s))
            self._errors[t][0] += int(np.sum(pred[n + j][valid] != truth[valid]))
            self._errors[t][1] += int(valid.sum())
            if t in self._actor:
                self._actor[t] += class_counts(pred[n + j], truth, actors)
                for cid, name in () if classes is None else ACTOR_CLASSES.items():
                    per = self._class.setdefault(name, {u: np.zeros((2, 2), np.int64) for u in ACTOR_TAUS_S})
                    per[t] += class_counts(pred[n + j], truth, actors & (classes == cid))
            if t == STATIC_ERROR_TAU_S:
                static_pred, static_truth = pred[n + j], truth
        if ego_speed_mps is not None:
            group = self._by_speed[
                EGO_SPEED_LABELS[int(np.searchsorted(EGO_SPEED_EDGES_MPS, ego_speed_mps, side="right"))]
            ]
            miou = image_miou(ious)
            if miou is not None:
                group[0].append(miou)
            static = valid & (instance == 0)
            group[1] += [
                np.sum(static_pred & ~static_truth & static),
                np.sum(~static_pred & static_truth & static),
                np.sum(static),
            ]
        if eta_hat is not None:  # valid = actor + static pixels, the MiD sums their parts
            for part, mask in (("actor", actors), ("static", valid & ~actors)):
                s, c = mid_terms(eta_hat, eta, mask)
                self._mid_parts[part][0] += s
                self._mid_parts[part][1] += c
        if latency_ms is not None:
            self._latency_ms.append(latency_ms)

    def result(self) -> dict:
        nan = float("nan")
        # per image: the mean IoU over the thresholds with a finite IoU; images with none skipped
        per_image = [m for m in map(image_miou, self._iou_by_threshold) if m is not None]
        mid_sum, mid_count = (sum(v) for v in zip(*self._mid_parts.values()))
        return {
            "miou": float(np.mean(per_image)) if per_image else nan,
            "mid": mid_sum / mid_count * MID_SCALE if mid_count else nan,
            "error_rate": {f"{t:g}": (e / n if n else nan) for t, (e, n) in self._errors.items()},
            "actor_iou": {f"{t:g}": two_class_iou(c) for t, c in self._actor.items()},
            "class_iou": {
                name: {f"{t:g}": two_class_iou(c) for t, c in per.items()} for name, per in self._class.items()
            },
            "latency_ms": float(np.mean(self._latency_ms)) if self._latency_ms else nan,
            "images": len(per_image),
            "breakdown": self._breakdown(),
        }

    def _breakdown(self) -> dict:
        nan = float("nan")

        def mean(values) -> float:
            return float(np.mean(values)) if len(values) else nan

        per_threshold = np.array(self._iou_by_threshold, dtype=np.float64).reshape(-1, len(self.miou_thresholds_s))
        by_threshold = {
            threshold_key(t): mean(col[np.isfinite(col)]) for t, col in zip(self.miou_thresholds_s, per_threshold.T)
        }
        # false inside px: pixels predicted inside that are outside, per pair with a non-empty
        # inside union (in the "0" group: the stray pixels of an empty geofence)
        by_share = {
            label: {
                "pairs": len(g[0]),
                "miou": mean(g[0]),
                "inside_iou": mean(g[1]),
                "pairs_with_inside_union": len(g[1]),
                "false_inside_px_median": float(np.median(g[2])) if g[2] else nan,
                "false_inside_px_p90": float(np.percentile(g[2], 90)) if g[2] else nan,
            }
            for label, g in self._by_share.items()
        }
        mid = {f"mid_{part}": (s / c * MID_SCALE if c else nan) for part, (s, c) in self._mid_parts.items()}
        out = {"miou_by_threshold_s": by_threshold, "by_inside_share": by_share, **mid}
        errors, pixels = self._margin
        out["errors_by_margin_log_eta"] = {
            label: {
                "share_of_errors": (e / errors.sum() if errors.sum() else nan),
                "error_rate": (e / p if p else nan),
                "share_of_pixels": (p / pixels.sum() if pixels.sum() else nan),
            }
            for label, e, p in zip(margin_labels(), errors, pixels)
        }
        images = [[image_miou(list(row)) for row in f] for f in self._forgiven]
        out["miou_forgiving_margin_log_eta"] = {
            f"{m:g}": mean([x[j] for x in images if x[j] is not None]) for j, m in enumerate(FORGIVEN_MARGINS)
        }
        if any(len(g[0]) or g[1][2] for g in self._by_speed.values()):
            key = f"{STATIC_ERROR_TAU_S:g}s"
            out["by_ego_speed_mps"] = {
                label: {
                    "images": len(ious),
                    "miou": mean(ious),
                    f"static_false_inside_{key}": (fi / px if px else nan),
                    f"static_missed_{key}": (mi / px if px else nan),
                }
                for label, (ious, (fi, mi, px)) in self._by_speed.items()
            }
        return out
