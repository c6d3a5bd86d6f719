"""An estimator's metrics on a dataset split (``bittc eval --data``): the pairs in dataset
order through ``geofence`` (every metric threshold) and ``motion_in_depth``, timed per
pair, into ``bittc_core.metrics.MetricAccumulator``; the result as a dict (miou, mid,
error_rate, actor_iou, class_iou, latency_ms, breakdown) and as a table."""

from __future__ import annotations

import time

from bittc_core.errors import ConfigError
from bittc_core.estimator import OracleEstimator
from bittc_core.export.parity import Agreement
from bittc_core.metrics import STATIC_ERROR_TAU_S, MetricAccumulator, threshold_key
from bittc_core.ttc import pair_spans_stride


def evaluate(estimator, dataset, limit: int | None, against=None, frame_stride: int = 1) -> dict:
    """The metrics of ``estimator`` on the first ``limit`` pairs; with ``against`` (another
    backend of the same network) also their agreement (``backend_agreement``).
    ``frame_stride``: each pair spans that many of the estimator's frame intervals and is
    read at its own interval (time compressed; the metrics' thresholds are the estimator's)."""
    acc = MetricAccumulator(dt_s=estimator.dt_s)
    agreement = Agreement(acc.thresholds_s) if against is not None else None
    n = len(dataset) if limit is None else min(limit, len(dataset))
    for i in range(n):
        s = dataset[i]
        dt = float(s["dt_s"])
        if not pair_spans_stride(dt, estimator.dt_s, frame_stride):
            raise ConfigError(
                f"sample {i}: dt_s={dt:g} s but the estimator works at {estimator.dt_s:g} s"
                + (f" x frame stride {frame_stride}" if frame_stride != 1 else "")
            )
        if isinstance(estimator, OracleEstimator):
            estimator.set_ground_truth(s["eta"])
        t0 = time.perf_counter()
        prob = estimator.geofence(s["image_prev"], s["image_latest"], acc.thresholds_s)
        eta_hat = estimator.motion_in_depth(s["image_prev"], s["image_latest"])
        latency = (time.perf_counter() - t0) * 1e3
        if agreement is not None:
            agreement.add(
                prob,
                against.geofence(s["image_prev"], s["image_latest"], acc.thresholds_s),
                eta_hat,
                against.motion_in_depth(s["image_prev"], s["image_latest"]),
            )
        speed = s.get("ego_speed_mps")
        acc.add(
            prob,
            eta_hat,
            s["eta"].numpy(),
            s["valid"].numpy().astype(bool),
            s["instance"].numpy(),
            latency_ms=latency,
            ego_speed_mps=None if speed is None else float(speed),
            classes=s["actor_class"].numpy() if "actor_class" in s else None,
        )
    result = acc.result()
    result["pairs"] = n
    if agreement is not None:
        result["backend_agreement"] = agreement.result()
    result["miou_thresholds_s"] = [float(threshold_key(t)) for t in acc.miou_thresholds_s]
    return result


def format_table(r: dict) -> str:
    """The result of ``evaluate`` as the table ``bittc eval --data`` prints."""
    lines = [
        f"{'metric':<22} {'value':>10}",
        f"{'mIoU (0.2-2 s)':<22} {r['miou']:>10.4f}",
        f"{'MiD (x1e4)':<22} {r['mid']:>10.1f}",
    ]
    lines += [f"{'error rate tau=' + k + ' s':<22} {v:>10.4f}" for k, v in r["error_rate"].items()]
    lines += [f"{'actor IoU tau=' + k + ' s':<22} {v:>10.4f}" for k, v in r["actor_iou"].items()]
    for name, per in r.get("class_iou", {}).items():
        lines += [f"{name + ' IoU tau=' + k + ' s':<22} {v:>10.4f}" for k, v in per.items()]
    lines.append(f"{'latency ms/pair':<22} {r['latency_ms']:>10.2f}")
    if "backend_agreement" in r:
        a = r["backend_agreement"]
        lines.append(
            f"against torch: geofence pixels agreeing (min over thresholds) {a['geofence_pixels_agreeing_min']:.6f}, "
            f"|log eta| difference max {a['log_eta_abs_diff_max']:.2e}, p99.9 {a['log_eta_abs_diff_p999']:.2e}"
        )
    b = r.get("breakdown")
    if b:
        lines.append(f"{'MiD actor / static':<22} {b['mid_actor']:>10.1f} / {b['mid_static']:.1f}")
        lines.append("mIoU by threshold [s]: " + ", ".join(f"{t} {v:.3f}" for t, v in b["miou_by_threshold_s"].items()))
        lines.append("mIoU pairs by share of pixels inside the geofence:")
        for label, g in b["by_inside_share"].items():
            lines.append(
                f"  {label:>8}: {g['pairs']:>6} pairs, mIoU {g['miou']:.3f}, inside-class IoU "
                f"{g['inside_iou']:.3f} over {g['pairs_with_inside_union']} pairs, "
                f"false inside px median {g['false_inside_px_median']:.0f}, p90 {g['false_inside_px_p90']:.0f}"
            )
        if "by_ego_speed_mps" in b:
            key = f"{STATIC_ERROR_TAU_S:g}s"
            lines.append(
                "images by ego speed [m/s]: mIoU, static pixels at tau = "
                f"{STATIC_ERROR_TAU_S:g} s false inside / missed:"
            )
            for label, g in b["by_ego_speed_mps"].items():
                lines.append(
                    f"  {label:>8}: {g['images']:>6} images, mIoU {g['miou']:.3f}, "
                    f"{g['static_false_inside_' + key]:.3f} / {g['static_missed_' + key]:.3f}"
                )
        if "errors_by_margin_log_eta" in b:
            lines.append(
                "errors of the mIoU maps by margin |log eta - log eta_i|: "
                "share of errors / error rate / share of pixels:"
            )
            for label, g in b["errors_by_margin_log_eta"].items():
                lines.append(
                    f"  {label:>10}: {g['share_of_errors']:.3f} / {g['error_rate']:.3f} / {g['share_of_pixels']:.3f}"
                )
            lines.append(
                "mIoU if the errors within a margin were right: "
                + ", ".join(f"< {m} {v:.3f}" for m, v in b["miou_forgiving_margin_log_eta"].items())
            )
    return "\n".join(lines)
