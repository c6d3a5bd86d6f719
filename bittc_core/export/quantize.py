"""INT8 graphs of an export: onnxruntime static quantization calibrated on the graphs' real inputs.

``quantize_export`` turns a float32 export folder into an int8 one. The per-threshold
graphs (``QUANTIZED_GRAPHS``: thresholds, continuous) of each image size go through
``onnxruntime.quantization.quantize_static``: QDQ format, int8 weights per output channel,
uint8 activations (the u8 x s8 product of the x86 VNNI kernels), each activation's range
the min / max over the calibration inputs. The calibration inputs are what the graphs
really see: the float graphs run the estimator's streaming steps (extractor on both
frames, reference on the latest, thresholds, continuous) on rendered frame pairs, and
each graph's feeds are kept (``graph_inputs``). The thresholds graph is calibrated at the
parity thresholds and at ``SPREAD_THRESHOLDS`` thresholds spread over the trained range.

What stays float32, measured on the shipped weights (docs/onnx_int8.md):

* every op but ``Conv`` (``QUANTIZED_OPS``): the warps' geometry (the eta input, the
  sampling grids, ``GridSample``), the correlation volume's arithmetic, the upsampling and
  the continuous head's AUC. Eta steps between fences are a few thousandths (tau 1.6 s
  and 1.8 s at 0.1 s: eta 0.941 and 0.947), under one step of an 8-bit code over the
  trained range. ``ConvTranspose`` too: onnxruntime's CPU provider runs it in float
  behind a DequantizeLinear, so quantizing its input only adds rounding;
* the convolutions at the graphs' ends (``end_convs``: taking or producing at most 3
  channels, the heads producing the logit maps and the refiners' stems), the largest
  single contributions to changed decisions;
* the extractor and the reference graphs: the features feed the matching, and an int8
  extractor changed 1.0 % of the fovea's decisions against 0.6 % without (for 0.2 ms of
  2 ms); the int8 reference graph ran 1 ms slower than the float one.

Parity (``decision_changes``): on held-out frame pairs (other scenes than the
calibration's), the share of pixels whose fence decision (p > 0.5) differs between the
float32 and the int8 graphs, per image size and threshold; ``PARITY_TARGET`` at most.
"""

from __future__ import annotations

import contextlib
import json
import logging
import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bittc_core.export.graphs import GRAPHS
from bittc_core.export.manifest import MANIFEST, ExportError, sha256_file, sizes_of
from bittc_core.ttc import tau_to_eta

Pair = tuple[np.ndarray, np.ndarray]  # (image_prev, image_latest), uint8 (H, W, 3) RGB

QUANTIZED_GRAPHS = ("thresholds", "continuous")  # the graphs quantized; the others are copied as they are
QUANTIZED_OPS = ("Conv",)  # the op types quantized in them; every other op runs in float
END_CHANNELS = 3  # convolutions taking or producing at most this many channels stay float
CALIBRATION_METHOD = "MinMax"
SPREAD_THRESHOLDS = 8  # thresholds, geometric over the trained range, the thresholds graph is also calibrated at
PARITY_TARGET = 0.01  # [-] the largest share of pixels whose fence decision may change, per size and threshold
DECISION_PROB = 0.5  # a pixel is inside a fence where p > DECISION_PROB


@dataclass(frozen=True)
class FramePairs:
    """Frame pairs of one or more image sizes, and where they come from (recorded in the
    manifest: e.g. the scenario cases, frames and seed they were rendered from)."""

    pairs: tuple[Pair, ...]
    source: str

    def by_size(self) -> dict[tuple[int, int], list[Pair]]:
        """(H, W) [px] -> the pairs of that size, in order."""
        out: dict[tuple[int, int], list[Pair]] = {}
        for prev, latest in self.pairs:
            if prev.dtype != np.uint8 or prev.ndim != 3 or prev.shape[2] != 3 or prev.shape != latest.shape:
                raise ExportError(
                    f"frame pair {prev.shape} {prev.dtype} / {latest.shape} {latest.dtype}: "
                    "expected two uint8 (H, W, 3) RGB frames of one size"
                )
            out.setdefault(tuple(prev.shape[:2]), []).append((prev, latest))
        return out


@dataclass(frozen=True)
class Int8Settings:
    """What an int8 export is calibrated and checked on.

    calibration: the frame pairs whose graph inputs set the activation ranges; held_out:
    other pairs (other scenes), on which the parity is measured; both need pairs of every
    exported size. thresholds_s: [s] the parity's fences in the estimator's time base
    (pairs ``frame_dt_s`` apart; a controller pairing frames further apart maps its own);
    the thresholds graph is calibrated at them too."""

    calibration: FramePairs
    held_out: FramePairs
    thresholds_s: tuple[float, ...]


def size_key(size_hw: tuple[int, int]) -> str:
    return f"{size_hw[0]}x{size_hw[1]}"


def _image(frame: np.ndarray) -> np.ndarray:
    """uint8 (H, W, 3) -> float32 (1, 3, H, W) in [0, 1], as the estimator feeds the graphs."""
    return np.ascontiguousarray(frame.transpose(2, 0, 1)[None], dtype=np.float32) / np.float32(255.0)


def graph_inputs(sessions: dict, pairs: list[Pair], eta: np.ndarray) -> dict[str, list[dict]]:
    """graph -> the feeds of each call the streaming estimator makes on ``pairs`` (one view;
    the thresholds graph at all of ``eta`` (K,) at once), computed by the float ``sessions``
    (graph -> onnxruntime session) of the pairs' size."""
    ref_names = [o.name for o in sessions["reference"].get_outputs()]
    eta = np.asarray(eta, np.float32)[None]
    feeds: dict[str, list[dict]] = {g: [] for g in GRAPHS}
    for prev, latest in pairs:
        image_prev, image_latest = _image(prev), _image(latest)
        feeds["extractor"] += [{"image": image_prev}, {"image": image_latest}]
        feat_prev = sessions["extractor"].run(None, {"image": image_prev})[0]
        feat_latest = sessions["extractor"].run(None, {"image": image_latest})[0]
        ref_feeds = {"features_latest": feat_latest, "image_latest": image_latest}
        feeds["reference"].append(ref_feeds)
        refs = dict(zip(ref_names, sessions["reference"].run(None, ref_feeds)))
        feeds["thresholds"].append(refs | {"features_prev": feat_prev, "eta": eta})
        feeds["continuous"].append(refs | {"image_latest": image_latest, "features_prev": feat_prev})
    return feeds


def end_convs(model, max_channels: int = END_CHANNELS) -> list[str]:
    """The names of the convolutions at the graph's ends: those taking or producing at most
    ``max_channels`` channels (the stems on an image or a map, the heads producing logits)."""
    shapes = {i.name: tuple(i.dims) for i in model.graph.initializer}
    return [
        n.name
        for n in model.graph.node
        if n.op_type in QUANTIZED_OPS and n.input[1] in shapes and min(shapes[n.input[1]][:2]) <= max_channels
    ]


@contextlib.contextmanager
def _quiet_root_logger():
    """quantize_static logs advice on the root logger on every call; the export prints its own."""
    root = logging.getLogger()
    level = root.level
    root.setLevel(logging.ERROR)
    try:
        yield
    finally:
        root.setLevel(level)


def quantize_graph(float_path: Path, out_path: Path, feeds: list[dict], nodes_to_exclude: list[str]) -> None:
    """One float32 graph -> its int8 QDQ graph at ``out_path``, calibrated on ``feeds``."""
    from onnxruntime import quantization as q

    class Reader(q.CalibrationDataReader):
        def __init__(self) -> None:
            self._it = iter(feeds)

        def get_next(self) -> dict | None:
            return next(self._it, None)

    with _quiet_root_logger():
        q.quantize_static(
            str(float_path),
            str(out_path),
            Reader(),
            quant_format=q.QuantFormat.QDQ,
            op_types_to_quantize=list(QUANTIZED_OPS),
            per_channel=True,
            reduce_range=False,
            activation_type=q.QuantType.QUInt8,
            weight_type=q.QuantType.QInt8,
            nodes_to_exclude=nodes_to_exclude,
            calibrate_method=getattr(q.CalibrationMethod, CALIBRATION_METHOD),
        )


def decision_changes(float_est, int8_est, pairs: list[Pair], thresholds_s) -> np.ndarray:
    """-> (K,) the share of the pixels of ``pairs`` whose decision p > 0.5 differs between the
    two estimators, per threshold of ``thresholds_s`` [s]."""
    changed = np.zeros(len(thresholds_s))
    pixels = 0
    for prev, latest in pairs:
        a = float_est.geofence(prev, latest, thresholds_s) > DECISION_PROB
        b = int8_est.geofence(prev, latest, thresholds_s) > DECISION_PROB
        changed += (a != b).reshape(len(thresholds_s), -1).sum(axis=1)
        pixels += a[0].size
    return changed / max(pixels, 1)


def _float_sessions(folder: Path, size_entry: dict, threads: int | None) -> dict:
    import onnxruntime as ort
    import torch

    opts = ort.SessionOptions()
    opts.intra_op_num_threads = threads or torch.get_num_threads()
    opts.inter_op_num_threads = 1
    files = {g: folder / size_entry["graphs"][g]["file"] for g in GRAPHS}
    return {g: ort.InferenceSession(str(f), opts, providers=["CPUExecutionProvider"]) for g, f in files.items()}


def _pairs_per_size(name: str, frames: FramePairs, sizes: list[tuple[int, int]]) -> dict:
    by_size = frames.by_size()
    for size in sizes:
        if not by_size.get(size):
            raise ExportError(f"{name} frame pairs: none of {size_key(size)} px, an exported size")
    extra = sorted(set(by_size) - set(sizes))
    if extra:
        raise ExportError(f"{name} frame pairs of {', '.join(map(size_key, extra))} px: not an exported size")
    return by_size


def check_settings(settings: Int8Settings, sizes: list[tuple[int, int]]) -> None:
    """Refuse settings without calibration or held-out pairs of every size in ``sizes`` (or
    with pairs of other sizes), before anything is exported."""
    _pairs_per_size("calibration", settings.calibration, sizes)
    _pairs_per_size("held-out", settings.held_out, sizes)


def quantize_export(float_folder: Path, out: Path, settings: Int8Settings, threads: int | None = None) -> dict:
    """The float32 export in ``float_folder`` -> an int8 export written into the folder ``out``
    (graphs and manifest); -> its manifest, with the calibration and the parity."""
    import onnx

    from bittc_core.estimator.onnx import OnnxBittcEstimator

    fm = json.loads((float_folder / MANIFEST).read_text())
    sizes = sizes_of(fm)
    thresholds_s = tuple(float(t) for t in settings.thresholds_s)
    calibration = _pairs_per_size("calibration", settings.calibration, sizes)
    held_out = _pairs_per_size("held-out", settings.held_out, sizes)
    float_est = OnnxBittcEstimator(float_folder, threads=threads)  # also checks the thresholds' range
    spread = np.geomspace(*fm["tau_range_s"], SPREAD_THRESHOLDS)
    eta = tau_to_eta(np.concatenate([thresholds_s, spread]), fm["frame_dt_s"])
    excluded: dict[str, list[str]] = {}
    size_entries = []
    for size, entry in zip(sizes, fm["sizes"]):
        feeds = graph_inputs(_float_sessions(float_folder, entry, threads), calibration[size], eta)
        graphs = {}
        for name in GRAPHS:
            g = entry["graphs"][name]
            src, dst = float_folder / g["file"], out / g["file"]
            if name in QUANTIZED_GRAPHS:
                excluded[name] = end_convs(onnx.load(str(src)))
                quantize_graph(src, dst, feeds[name], excluded[name])
            else:
                shutil.copyfile(src, dst)
            precision = "int8" if name in QUANTIZED_GRAPHS else "float32"
            graphs[name] = g | {"sha256": sha256_file(dst), "precision": precision}
        size_entries.append(entry | {"graphs": graphs})
    quantization = {
        "tool": "onnxruntime.quantization.quantize_static",
        "format": "QDQ",
        "weights": "int8, per output channel, symmetric",
        "activations": f"uint8, per tensor, asymmetric, {CALIBRATION_METHOD} over the calibration inputs",
        "graphs": list(QUANTIZED_GRAPHS),
        "op_types": list(QUANTIZED_OPS),
        "nodes_excluded": excluded,
        "calibration": {
            "source": settings.calibration.source,
            "pairs": {size_key(s): len(calibration[s]) for s in sizes},
            "thresholds_s": [round(float(t), 6) for t in np.concatenate([thresholds_s, spread])],
        },
    }
    manifest = fm | {"precision": "int8", "sizes": size_entries, "quantization": quantization}
    (out / MANIFEST).write_text(json.dumps(manifest, indent=2) + "\n")
    int8_est = OnnxBittcEstimator(out, threads=threads)
    changed = {size_key(s): decision_changes(float_est, int8_est, held_out[s], thresholds_s) for s in sizes}
    quantization["parity"] = {
        "source": settings.held_out.source,
        "pairs": {size_key(s): len(held_out[s]) for s in sizes},
        "thresholds_s": list(thresholds_s),
        "decision_changed": {
            k: {f"{t:g}": round(float(c), 6) for t, c in zip(thresholds_s, v)} for k, v in changed.items()
        },
        "decision_changed_max": round(float(max(v.max() for v in changed.values())), 6),
        "target": PARITY_TARGET,
    }
    (out / MANIFEST).write_text(json.dumps(manifest, indent=2) + "\n")
    return manifest
