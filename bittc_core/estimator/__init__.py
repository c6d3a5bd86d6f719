"""Estimators of binary / quantized / continuous TTC behind one interface.

``make_estimator("bittc" | "flow" | "oracle" | "oracle-auc", weights=None, device="auto", tta="none",
backend="torch", onnx=None)``; ``backend="onnxruntime", onnx=DIR``: the network exported to
``DIR`` (``bittc export --onnx DIR``) on onnxruntime, checked against ``weights`` when given;
``oracle-auc``: exact geofences, continuous output from their AUC at the shipped network's levels;
``tta="flip"`` (network only) averages each call over the plain and the mirrored frames.
"""

from __future__ import annotations

from bittc_core.checkpoint import DEFAULT_WEIGHTS, load_checkpoint
from bittc_core.estimator.base import Estimator, EstimatorInputError, quantize
from bittc_core.estimator.flow import FlowBaselineConfig, FlowEstimator
from bittc_core.estimator.network import TTA_MODES, BittcEstimator
from bittc_core.estimator.oracle import OracleEstimator

METHODS = ("bittc", "flow", "oracle", "oracle-auc")
BACKENDS = ("torch", "onnxruntime")


def make_estimator(
    method: str,
    weights: str | None = None,
    device: str = "auto",
    tta: str = "none",
    backend: str = "torch",
    onnx: str | None = None,
) -> Estimator:
    if method not in METHODS:
        raise EstimatorInputError(f"unknown method {method!r}; expected one of {METHODS}")
    if backend not in BACKENDS:
        raise EstimatorInputError(f"backend {backend!r}: expected one of {BACKENDS}")
    if backend == "onnxruntime":
        if method != "bittc":
            raise EstimatorInputError(f"backend 'onnxruntime' runs the network (method 'bittc'), not {method!r}")
        if onnx is None:
            raise EstimatorInputError(
                "backend 'onnxruntime' needs onnx=DIR, an export folder (`bittc export` makes one)"
            )
        if device not in ("auto", "cpu"):
            raise EstimatorInputError(f"device {device!r}: the onnxruntime backend runs on the CPU")
        from bittc_core.estimator.onnx import OnnxBittcEstimator

        return OnnxBittcEstimator(onnx, weights=weights, tta=tta)
    if onnx is not None:
        raise EstimatorInputError(f"onnx={onnx!r} applies to backend 'onnxruntime', not {backend!r}")
    if method == "bittc":
        return BittcEstimator.from_checkpoint(weights, device=device, tta=tta)
    if weights is not None:
        raise EstimatorInputError(f"weights {weights!r} only apply to method 'bittc', not {method!r}")
    if tta != "none":
        raise EstimatorInputError(f"tta={tta!r} only applies to method 'bittc', not {method!r}")
    if method == "flow":
        return FlowEstimator()
    if method == "oracle-auc":
        c = load_checkpoint(DEFAULT_WEIGHTS, map_location="cpu")["model_config"]
        return OracleEstimator(dt_s=c.frame_dt_s, auc_volume=(c.cont_eta_min, c.cont_eta_max, c.cont_levels))
    return OracleEstimator()


__all__ = [
    "Estimator",
    "EstimatorInputError",
    "quantize",
    "BittcEstimator",
    "FlowEstimator",
    "FlowBaselineConfig",
    "OracleEstimator",
    "make_estimator",
    "METHODS",
    "BACKENDS",
    "TTA_MODES",
]
