"""``bittc`` on onnxruntime: the exported graphs (``bittc export --onnx DIR``) behind the
same estimator interface, streaming cache and input checks as the torch backend
(``bittc_core.estimator.streaming``).

``make_estimator("bittc", backend="onnxruntime", onnx=DIR)``. The folder's manifest is
checked when it is opened (``bittc_core.export.manifest``): every graph present with its
hash and, when ``weights`` is given, exported from those weights. The graphs run on the
CPU with ``threads`` intra-op threads (default: torch's thread count, so that both
backends compare on the same cores). The export holds the graphs of one or more image
sizes (``sizes_px``; a float32 or an int8 folder alike): each call runs the sessions of its
frames' size, and a size not exported is refused by name. The sessions are opened with the
estimator and shared by its forks (the geofence controller's fovea of another size
included). Thresholds go through the ``thresholds`` graph ``HYPOTHESES_PER_RUN`` at a
time.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import torch

from bittc_core.estimator.base import EstimatorInputError
from bittc_core.estimator.streaming import StreamingNetEstimator
from bittc_core.export.graphs import GRAPHS
from bittc_core.export.manifest import ExportError, check_matches_checkpoint, read_manifest, sizes_of

HYPOTHESES_PER_RUN = 8  # thresholds per run of the thresholds graph (as the torch backend's CPU batches)


def require_onnxruntime():
    try:
        import onnxruntime
    except ImportError:
        raise ExportError("the onnxruntime backend needs onnxruntime: pip install -e '.[onnx]'") from None
    return onnxruntime


def _session(ort, path: Path, opts):
    try:
        return ort.InferenceSession(str(path), opts, providers=["CPUExecutionProvider"])
    except Exception as e:  # onnxruntime raises its own Fail / InvalidGraph types
        raise ExportError(
            f"{str(path)!r}: onnxruntime cannot load it ({type(e).__name__}: {str(e).splitlines()[0][:200]})"
        ) from None


class OnnxBittcEstimator(StreamingNetEstimator):
    name = "bittc"
    backend = "onnxruntime"

    def __init__(
        self,
        folder: str | os.PathLike,
        *,
        weights: str | os.PathLike | None = None,
        tta: str = "none",
        threads: int | None = None,
    ) -> None:
        ort = require_onnxruntime()
        folder = Path(folder)
        manifest = read_manifest(folder, graphs=GRAPHS)
        if weights is not None:
            from bittc_core.checkpoint import load_checkpoint

            check_matches_checkpoint(manifest, folder, load_checkpoint(weights, map_location="cpu"), weights)
        super().__init__(
            dt_s=manifest["frame_dt_s"], tau_range_s=tuple(manifest["tau_range_s"]), device=torch.device("cpu"), tta=tta
        )
        self.manifest = manifest
        self.folder = folder
        self.precision = manifest["precision"]
        self.sizes_px = tuple(sizes_of(manifest))  # (H, W) [px] of every exported size
        opts = ort.SessionOptions()
        opts.intra_op_num_threads = threads or torch.get_num_threads()
        opts.inter_op_num_threads = 1
        opts.graph_optimization_level = ort.GraphOptimizationLevel.ORT_ENABLE_ALL
        # idle pool threads sleep instead of spinning: the estimator shares the CPU with the
        # renderer (and, in `bittc bench`, with torch), which spinning threads would slow down
        opts.add_session_config_entry("session.intra_op.allow_spinning", "0")
        # (H, W) -> graph -> session
        self.sessions: dict[tuple[int, int], dict] = {
            size: {name: _session(ort, folder / entry["graphs"][name]["file"], opts) for name in GRAPHS}
            for size, entry in zip(self.sizes_px, manifest["sizes"])
        }
        self._ref_names = [o.name for o in self.sessions[self.sizes_px[0]]["reference"].get_outputs()]

    def _check_size(self, image: torch.Tensor) -> None:
        super()._check_size(image)
        size = tuple(image.shape[-2:])
        if size not in self.sessions:
            raise EstimatorInputError(
                f"image size {size} px: the ONNX export in {str(self.folder)!r} takes "
                f"{' or '.join(str(s) for s in self.sizes_px)} px; export it at this size too "
                "(`bittc export` takes sizes)"
            )

    def _run(self, graph: str, image: np.ndarray, feeds: dict) -> list[np.ndarray]:
        """``graph`` at the size of ``image`` (..., H, W)."""
        return self.sessions[image.shape[-2:]][graph].run(None, feeds)

    def _extract(self, views: torch.Tensor) -> np.ndarray:
        image = np.ascontiguousarray(views.numpy())
        return self._run("extractor", image, {"image": image})[0]

    def _make_reference(self, feats: np.ndarray, views: torch.Tensor) -> dict:
        image = np.ascontiguousarray(views.numpy())
        refs = self._run("reference", image, {"features_latest": feats, "image_latest": image})
        return dict(zip(self._ref_names, refs)) | {"image_latest": image}

    def _classify(self, ctx: dict, feat_prev: np.ndarray, eta: torch.Tensor) -> torch.Tensor:
        feeds = {n: ctx[n] for n in self._ref_names} | {"features_prev": feat_prev}
        eta = np.ascontiguousarray(eta.numpy(), dtype=np.float32)
        parts = [
            self._run("thresholds", ctx["image_latest"], feeds | {"eta": eta[:, i : i + HYPOTHESES_PER_RUN]})[0]
            for i in range(0, eta.shape[1], HYPOTHESES_PER_RUN)
        ]
        return torch.from_numpy(np.concatenate(parts, axis=1) if len(parts) > 1 else parts[0])

    def _log_eta(self, ctx: dict, feat_prev: np.ndarray) -> torch.Tensor:
        feeds = {n: ctx[n] for n in self._ref_names} | {"image_latest": ctx["image_latest"], "features_prev": feat_prev}
        return torch.from_numpy(self._run("continuous", ctx["image_latest"], feeds)[0])
