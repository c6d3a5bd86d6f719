"""The bundled geofence controllers, by name (``controllers.REGISTRY``): the shipped
network (``geofence``), DIS + affine expansion (``flow``) or the exact fences of the
ground truth (``geofence-exact``, an upper bound: ``controllers.geofence_exact``) behind
the same policy (``controllers.geofence.GeofenceController``)."""

from __future__ import annotations

from controllers.geofence import GeofenceController
from controllers.geofence_config import GeofenceConfig, default_thresholds
from controllers.tracker_config import TrackerConfig


def _config(
    thresholds_s,
    frame_stride: int | None,
    fovea_fences_from_s: float | None = None,
    road_edge_rows: int | None = None,
    turn_across: bool | None = None,
    oncoming: bool | None = None,
    fovea_short_pair: bool | None = None,
) -> GeofenceConfig:
    thr = tuple(thresholds_s) if thresholds_s is not None else default_thresholds(4)
    kw = {} if frame_stride is None else {"frame_stride": frame_stride}
    if fovea_fences_from_s is not None:
        kw["fovea_fences_from_s"] = float(fovea_fences_from_s)
    if road_edge_rows is not None:
        kw["road_edge_rows"] = road_edge_rows
    if fovea_short_pair is not None:
        kw["fovea_short_pair"] = bool(fovea_short_pair)
    tracker = {k: bool(v) for k, v in (("turn_across", turn_across), ("oncoming", oncoming)) if v is not None}
    if tracker:
        kw["tracker"] = TrackerConfig(**tracker)
    return GeofenceConfig(thresholds_s=thr, **kw)


def make_geofence(
    thresholds_s=None,
    weights: str | None = None,
    frame_stride: int | None = None,
    device: str = "cpu",
    name: str = "geofence",
    backend: str = "torch",
    onnx: str | None = None,
    fovea_fences_from_s: float | None = None,
    road_edge_rows: int | None = None,
    turn_across: bool | None = None,
    oncoming: bool | None = None,
    fovea_short_pair: bool | None = None,
) -> GeofenceController:
    """The shipped network (or ``weights``) behind the geofence controller; ``backend=
    "onnxruntime", onnx=DIR``: the same weights exported to ``DIR`` (checked against them)."""
    from bittc_core.checkpoint import DEFAULT_WEIGHTS
    from bittc_core.estimator import make_estimator

    if backend == "onnxruntime":
        est = make_estimator("bittc", weights=weights or DEFAULT_WEIGHTS, backend=backend, onnx=onnx)
    else:
        est = make_estimator("bittc", weights=weights, device=device, backend=backend, onnx=onnx)
    cfg = _config(
        thresholds_s, frame_stride, fovea_fences_from_s, road_edge_rows, turn_across, oncoming, fovea_short_pair
    )
    return GeofenceController(est, cfg, name=name)


def make_flow(
    thresholds_s=None,
    frame_stride: int | None = None,
    name: str = "flow",
    fovea_fences_from_s: float | None = None,
    road_edge_rows: int | None = None,
    turn_across: bool | None = None,
    oncoming: bool | None = None,
    fovea_short_pair: bool | None = None,
) -> GeofenceController:
    """The DIS + affine-expansion baseline behind the same controller logic."""
    from bittc_core.estimator import make_estimator

    cfg = _config(
        thresholds_s, frame_stride, fovea_fences_from_s, road_edge_rows, turn_across, oncoming, fovea_short_pair
    )
    return GeofenceController(make_estimator("flow"), cfg, name=name)


def make_geofence_exact(
    thresholds_s=None,
    frame_stride: int | None = None,
    name: str = "geofence-exact",
    fovea_fences_from_s=None,
    road_edge_rows: int | None = None,
    turn_across: bool | None = None,
    oncoming: bool | None = None,
    fovea_short_pair: bool | None = None,
) -> GeofenceController:
    """The same policy on the exact fences of the per-pixel ground truth (not deployable)."""
    from controllers.geofence_exact import ExactFenceController

    cfg = _config(
        thresholds_s, frame_stride, fovea_fences_from_s, road_edge_rows, turn_across, oncoming, fovea_short_pair
    )
    return ExactFenceController(cfg, name=name)
