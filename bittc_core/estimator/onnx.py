"""``bittc`` on onnxruntime: the exported graphs (``bittc export --onnx DIR``) behind the
same estimator interface, streaming cache and input checks as the torch backend
(``bittc_core.estimator.streaming``).

``make_estimator("bittc", backend="onnxruntime", onnx=DIR)``. The folder's manifest is
checked when it is opened (``bittc_core.export.manifest``): every graph present with its
hash and, when ``weights`` is given, exported from those weights. The graphs run on the
CPU with ``threads`` intra-op threads (default: torch's thread count, so that both
backends compare on the same cores). The image size is the export's; another size is
refused by name. Thresholds go through the ``thresholds`` graph ``HYPOTHESES_PER_RUN`` at
a time.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import torch

from bittc_core.estimator.base import EstimatorInputError
from bittc_core.estimator.streaming import StreamingNetEstimator
from bittc_core.export.graphs import GRAPHS
from bittc_core.export.manifest import ExportError, check_matches_checkpoint, read_manifest

HYPOTHESES_PER_RUN = 8  # thresholds per run of the thresholds graph (as the torch backend's CPU batches)


def require_onnxruntime():
    try:
        import onnxruntime
    except ImportError:
        raise ExportError("the onnxruntime backend needs onnxruntime: pip install -e '.[onnx]'") from None
    return onnxruntime


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
        self.size_px = (manifest["image"]["height_px"], manifest["image"]["width_px"])
        opts = ort.SessionOptions()
        opts.intra_op_num_threads = threads or torch.get_num_threads()
        opts.inter_op_num_threads = 1
        opts.graph_optimization_level = ort.GraphOptimizationLevel.ORT_ENABLE_ALL
        # idle pool threads sleep instead of spinning: the estimator shares the CPU with the
        # renderer (and, in `bittc bench`, with torch), which spinning threads would slow down
        opts.add_session_config_entry("session.intra_op.allow_spinning", "0")
        self.sessions = {}
        for name in GRAPHS:
            path = folder / manifest["graphs"][name]["file"]
            try:
                self.sessions[name] = ort.InferenceSession(str(path), opts, providers=["CPUExecutionProvider"])
            except Exception as e:  # onnxruntime raises its own Fail / InvalidGraph types
                raise ExportError(
                    f"{str(path)!r}: onnxruntime cannot load it ({type(e).__name__}: {str(e).splitlines()[0][:200]})"
                ) from None
        self._ref_names = [o.name for o in self.sessions["reference"].get_outputs()]

    def _check_size(self, image: torch.Tensor) -> None:
        super()._check_size(image)
        if tuple(image.shape[-2:]) != self.size_px:
            raise EstimatorInputError(
                f"image size {tuple(image.shape[-2:])} px: the ONNX export in "
                f"{str(self.folder)!r} takes {self.size_px} px; export it at this size "
                "(`bittc export` takes a size)"
            )

    def _run(self, graph: str, feeds: dict) -> list[np.ndarray]:
        return self.sessions[graph].run(None, feeds)

    def _extract(self, views: torch.Tensor) -> np.ndarray:
        return self._run("extractor", {"image": np.ascontiguousarray(views.numpy())})[0]

    def _make_reference(self, feats: np.ndarray, views: torch.Tensor) -> dict:
        image = np.ascontiguousarray(views.numpy())
        refs = self._run("reference", {"features_latest": feats, "image_latest": image})
        return dict(zip(self._ref_names, refs)) | {"image_latest": image}

    def _classify(self, ctx: dict, feat_prev: np.ndarray, eta: torch.Tensor) -> torch.Tensor:
        feeds = {n: ctx[n] for n in self._ref_names} | {"features_prev": feat_prev}
        eta = np.ascontiguousarray(eta.numpy(), dtype=np.float32)
        parts = [
            self._run("thresholds", feeds | {"eta": eta[:, i : i + HYPOTHESES_PER_RUN]})[0]
            for i in range(0, eta.shape[1], HYPOTHESES_PER_RUN)
        ]
        return torch.from_numpy(np.concatenate(parts, axis=1) if len(parts) > 1 else parts[0])

    def _log_eta(self, ctx: dict, feat_prev: np.ndarray) -> torch.Tensor:
        feeds = {n: ctx[n] for n in self._ref_names} | {"image_latest": ctx["image_latest"], "features_prev": feat_prev}
        return torch.from_numpy(self._run("continuous", feeds)[0])
