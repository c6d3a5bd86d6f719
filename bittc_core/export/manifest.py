"""The manifest of an ONNX export folder (``manifest.json``) and its checks.

An export folder holds the graphs of ``bittc_core.export.graphs`` at one or more image
sizes, one file ``<graph>_<H>x<W>.onnx`` per graph and size, and ``manifest.json``::

    format          "bittc-onnx/2"
    precision       "float32", or "int8": every graph quantized (``quantization`` says how)
    model_config    asdict(ModelConfig) of the checkpoint; config_name its registry name
    weights         {"file": the checkpoint's name, "sha256": its hash, "release": its
                     release name (docs/releases.md) or null}
    image           {"layout": "NCHW", "channels": "RGB", "range": [0, 1],
                     "normalisation": "(x - 0.5) / 0.5, inside the graphs"}
    sizes           [{"height_px", "width_px", "graphs": graph -> {"file", "sha256",
                     "inputs": [{name, shape, dtype}], "outputs": [...]}}], one per image
                     size (the padded grid of the warps is fixed per size); a shape lists
                     ints and the names of dynamic axes ("views" V, "thresholds" K); in
                     an int8 export each graph also has its "precision" (graphs left in
                     float32 are copied as they are)
    frame_dt_s      [s] the frame interval the network was trained at
    eta_range       [eta(tau_min_s), eta(tau_max_s)]: the trained geofence range, with
                     tau_range_s; continuous: cont_eta_min, cont_eta_max, cont_levels
    opset           the ONNX opset
    quantization    null for float32; for int8 (``bittc_core.export.quantize``): the
                     method, the graphs and op types quantized, the nodes left in float,
                     the calibration frames and thresholds, and the parity against the
                     float32 graphs on held-out frames (the share of pixels whose fence
                     decision changed, per size and threshold, and the target)
    exporter        {"torch": version, "onnx": version, "created": ISO date}

Reading it checks the format, that every graph file of every size is there with its hash
(a truncated or edited file is refused), and, given a checkpoint, that the folder was
exported from that checkpoint (the same config and weights hash). A folder of the first
format ("bittc-onnx/1": one size, ``image`` holding it, ``graphs`` beside it, float32) is
read as a one-size folder of this one.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

from bittc_core.errors import ConfigError

FORMAT = "bittc-onnx/2"
FORMAT_ONE_SIZE = "bittc-onnx/1"  # read as a one-size float32 folder
MANIFEST = "manifest.json"
PRECISIONS = ("float32", "int8")
COMMON_KEYS = (
    "format",
    "config_name",
    "model_config",
    "weights",
    "image",
    "frame_dt_s",
    "tau_range_s",
    "eta_range",
    "continuous",
    "opset",
    "exporter",
)
KEYS = (*COMMON_KEYS, "precision", "sizes", "quantization")


class ExportError(ConfigError):
    """An export folder that is missing, corrupt, or of another checkpoint."""


def sha256_file(path: str | Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def graph_file(graph: str, height_px: int, width_px: int) -> str:
    """The file name of ``graph`` at one image size."""
    return f"{graph}_{height_px}x{width_px}.onnx"


def sizes_of(manifest: dict) -> list[tuple[int, int]]:
    """The image sizes (H, W) [px] of an export, in the manifest's order."""
    return [(s["height_px"], s["width_px"]) for s in manifest["sizes"]]


def size_entry(manifest: dict, size_hw: tuple[int, int]) -> dict | None:
    """The manifest's entry of one image size (H, W) [px], or None when not exported."""
    return next((s for s in manifest["sizes"] if (s["height_px"], s["width_px"]) == tuple(size_hw)), None)


def _from_one_size(m: dict) -> dict:
    """A "bittc-onnx/1" manifest (one size in ``image``, its ``graphs`` beside it) -> this format."""
    image = dict(m["image"])
    size = {"height_px": image.pop("height_px"), "width_px": image.pop("width_px"), "graphs": m["graphs"]}
    rest = {k: v for k, v in m.items() if k not in ("graphs", "image", "format")}
    return {"format": FORMAT, "precision": "float32", **rest, "image": image, "sizes": [size], "quantization": None}


def read_manifest(folder: str | Path, *, graphs: tuple[str, ...], verify_hashes: bool = True) -> dict:
    """Load and check ``folder/manifest.json`` and the graph files of every size; -> the
    manifest (of this format, a one-size folder of the first format included)."""
    folder = Path(folder)
    path = folder / MANIFEST
    if not folder.is_dir():
        raise ExportError(f"ONNX export folder {str(folder)!r}: no such folder (`bittc export` makes one)")
    if not path.is_file():
        raise ExportError(f"{str(path)!r}: no manifest; is {str(folder)!r} an ONNX export folder?")
    try:
        m = json.loads(path.read_text())
    except (ValueError, UnicodeDecodeError) as e:
        raise ExportError(f"{str(path)!r}: not valid JSON ({e})") from None
    fmt = m.get("format") if isinstance(m, dict) else None
    if fmt not in (FORMAT, FORMAT_ONE_SIZE):
        raise ExportError(
            f"{str(path)!r}: not a {FORMAT} manifest (format {fmt!r}); export the weights again (`bittc export`)"
        )
    keys = (*COMMON_KEYS, "graphs") if fmt == FORMAT_ONE_SIZE else KEYS
    missing = [k for k in keys if k not in m]
    if missing:
        raise ExportError(f"{str(path)!r}: lacks the keys {missing}")
    if fmt == FORMAT_ONE_SIZE:
        m = _from_one_size(m)
    if m["precision"] not in PRECISIONS:
        raise ExportError(f"{str(path)!r}: precision {m['precision']!r}, expected one of {PRECISIONS}")
    if not isinstance(m["sizes"], list) or not m["sizes"]:
        raise ExportError(f"{str(path)!r}: lists no image size")
    for size in m["sizes"]:
        if not isinstance(size, dict) or not {"height_px", "width_px", "graphs"} <= set(size):
            raise ExportError(f"{str(path)!r}: an incomplete size entry {size!r}")
        for name in graphs:
            _check_graph(folder, path, size, name, verify_hashes)
    return m


def _check_graph(folder: Path, path: Path, size: dict, name: str, verify_hashes: bool) -> None:
    g = size["graphs"].get(name)
    where = f"the graph {name!r} at {size['height_px']}x{size['width_px']} px"
    if not isinstance(g, dict) or not {"file", "sha256", "inputs", "outputs"} <= set(g):
        raise ExportError(f"{str(path)!r}: no complete entry for {where}")
    file = folder / g["file"]
    if not file.is_file():
        raise ExportError(f"{str(file)!r}: missing (the manifest lists it for {where})")
    if verify_hashes and sha256_file(file) != g["sha256"]:
        raise ExportError(f"{str(file)!r}: corrupt or edited (its sha256 is not the manifest's)")


def check_matches_checkpoint(manifest: dict, folder: str | Path, ckpt: dict, weights_path: str | Path) -> None:
    """Refuse an export made from another config or other weights than ``ckpt``."""
    from dataclasses import asdict

    if manifest["config_name"] != ckpt["config_name"] or manifest["model_config"] != json.loads(
        json.dumps(asdict(ckpt["model_config"]))
    ):
        raise ExportError(
            f"ONNX export {str(folder)!r} is of config {manifest['config_name']!r}, not of the "
            f"checkpoint {str(weights_path)!r} ({ckpt['config_name']!r}); export it again"
        )
    digest = sha256_file(weights_path)
    if manifest["weights"]["sha256"] != digest:
        raise ExportError(
            f"ONNX export {str(folder)!r} was made from other weights (sha256 "
            f"{manifest['weights']['sha256'][:12]}...) than {str(weights_path)!r} ({digest[:12]}...); "
            "export it again"
        )
