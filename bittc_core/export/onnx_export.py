"""Export a checkpoint's streaming network to an ONNX folder (``bittc export --onnx DIR``).

Each graph of ``bittc_core.export.graphs`` goes through the torch exporter (torch.export,
dynamic axes V and K) once per image size asked for (the warps' padded grid is fixed per
size), is checked with ``onnx.checker`` and listed with its hash under its size in the
manifest (``bittc_core.export.manifest``). The folder is written whole or not at all: into
a temporary folder beside it, renamed at the end; an existing export folder is replaced,
any other non-empty folder refused. With ``int8`` settings the float32 graphs are made in
a scratch folder inside it and quantized from there (``bittc_core.export.quantize``); the
folder holds the int8 export alone.
"""

from __future__ import annotations

import datetime
import json
import os
import shutil
import tempfile
import warnings
from dataclasses import asdict
from pathlib import Path

from bittc_core.export.manifest import FORMAT, MANIFEST, ExportError, graph_file, sha256_file

OPSET = 18
DEFAULT_SIZE_PX = (96, 288)  # (H, W): the default camera's frames, which the shipped weights were trained on
SIZE_STRIDE_PX = 3  # [px] image sides are multiples of the feature stride (bittc_core.model.network)
EXAMPLE_VIEWS = 2  # example sizes of the dynamic axes (not 0 or 1: torch.export would fix them)
EXAMPLE_THRESHOLDS = 3
VARARGS_GRAPHS = ("thresholds", "continuous")  # their forward takes *args (the reference terms vary by config)


def require_onnx() -> None:
    """Raise a clear error when the optional ONNX packages are missing."""
    missing = []
    for module in ("onnx", "onnxruntime", "onnxscript"):
        try:
            __import__(module)
        except ImportError:
            missing.append(module)
    if missing:
        raise ExportError(f"ONNX support needs {', '.join(missing)}: pip install -e '.[onnx]'")


def _specs(net, height_px: int, width_px: int):
    """graph -> (module, example args, input names, output names, dynamic shapes)."""
    import torch
    from torch.export import Dim

    from bittc_core.export import graphs as G

    views, thr = Dim("views", min=1, max=8), Dim("thresholds", min=1, max=256)
    v = EXAMPLE_VIEWS
    g = torch.Generator().manual_seed(0)
    image = torch.rand(v, 3, height_px, width_px, generator=g)
    ext = G.ExtractorGraph(net, height_px, width_px)
    with torch.no_grad():
        feats = ext(image)
        ref_graph = G.ReferenceGraph(net, height_px, width_px)
        refs = ref_graph(feats, image)
    names = ref_graph.ref_names
    eta = torch.linspace(0.7, 1.0, EXAMPLE_THRESHOLDS)[None].repeat(v, 1)
    on_views = lambda n: tuple({0: views} for _ in range(n))  # noqa: E731
    return {
        "extractor": (ext, (image,), ["image"], ["features"], on_views(1)),
        "reference": (ref_graph, (feats, image), ["features_latest", "image_latest"], list(names), on_views(2)),
        "thresholds": (
            G.ThresholdsGraph(net, height_px, width_px),
            (*refs, feats, eta),
            [*names, "features_prev", "eta"],
            ["logits"],
            (*on_views(len(names) + 1), {0: views, 1: thr}),
        ),
        "continuous": (
            G.ContinuousGraph(net, height_px, width_px),
            (*refs, image, feats),
            [*names, "image_latest", "features_prev"],
            ["log_eta"],
            on_views(len(names) + 2),
        ),
    }


def _io(values, names, dynamic) -> list[dict]:
    out = []
    for value, name, dims in zip(values, names, dynamic):
        shape = [({0: "views", 1: "thresholds"}.get(i) if i in dims else int(s)) for i, s in enumerate(value.shape)]
        out.append({"name": name, "shape": shape, "dtype": "float32"})
    return out


def check_sizes(sizes=None, height_px: int | None = None, width_px: int | None = None) -> list[tuple[int, int]]:
    """The image sizes (H, W) [px] of an export: ``sizes``, or the one size ``height_px`` x
    ``width_px`` (each side defaulting to ``DEFAULT_SIZE_PX``'s), not both; distinct, positive
    multiples of ``SIZE_STRIDE_PX``."""
    if sizes is None:
        sizes = [(height_px or DEFAULT_SIZE_PX[0], width_px or DEFAULT_SIZE_PX[1])]
    elif height_px is not None or width_px is not None:
        raise ExportError(f"sizes {sizes!r} with height_px / width_px: give the sizes one way")
    out = []
    for size in sizes:
        try:
            h, w = (int(v) for v in size)
        except (TypeError, ValueError):
            raise ExportError(f"image size {size!r}: expected (height_px, width_px)") from None
        if (h, w) != tuple(size) or h <= 0 or w <= 0 or h % SIZE_STRIDE_PX or w % SIZE_STRIDE_PX:
            raise ExportError(
                f"image size {size!r}: height and width must be positive multiples of {SIZE_STRIDE_PX} px"
            )
        if (h, w) in out:
            raise ExportError(f"image size {h}x{w} px: given twice")
        out.append((h, w))
    if not out:
        raise ExportError("sizes is empty: give at least one image size (height_px, width_px)")
    return out


def export_onnx(
    weights: str | Path,
    out: str | Path,
    *,
    sizes=None,
    height_px: int | None = None,
    width_px: int | None = None,
    int8=None,
) -> dict:
    """Export ``weights`` into the folder ``out`` at every image size of ``sizes`` ((H, W)
    [px] pairs; or the one size ``height_px`` x ``width_px``, default ``DEFAULT_SIZE_PX``);
    ``int8``: ``quantize.Int8Settings``, an int8 export calibrated and checked on its frame
    pairs; -> the manifest. Steps: check the folder, export and check each graph into a
    private temporary folder (and quantize them), write the manifest, swap the folder in
    whole."""
    require_onnx()
    from bittc_core.checkpoint import build_network, load_checkpoint

    sizes = check_sizes(sizes, height_px, width_px)
    if int8 is not None:
        from bittc_core.export.quantize import check_settings

        check_settings(int8, sizes)
    out = Path(out)
    if out.exists() and (not out.is_dir() or (any(out.iterdir()) and not (out / MANIFEST).is_file())):
        raise ExportError(f"{str(out)!r}: exists and is not an ONNX export folder; choose another folder")
    ckpt = load_checkpoint(weights, map_location="cpu")
    net = build_network(ckpt).eval()
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", suffix=".partial", dir=out.parent))
    except OSError as e:
        raise ExportError(f"{str(out)!r}: cannot write there ({e.strerror})") from None
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o777 & ~umask)  # mkdtemp makes it private; the export is an ordinary folder
    try:
        graphs = tmp / ".float32" if int8 is not None else tmp
        graphs.mkdir(exist_ok=True)
        manifest = _manifest(ckpt, weights, [export_size(net, h, w, graphs) for h, w in sizes])
        (graphs / MANIFEST).write_text(json.dumps(manifest, indent=2) + "\n")
        if int8 is not None:
            from bittc_core.export.quantize import quantize_export

            manifest = quantize_export(graphs, tmp, int8)
            shutil.rmtree(graphs)
        _swap_in(tmp, out)
        return manifest
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def export_size(net, height_px: int, width_px: int, folder: Path) -> dict:
    """Every graph of ``net`` at one image size into ``folder``; -> the manifest's size entry."""
    from bittc_core.export.graphs import GRAPHS

    specs = _specs(net, height_px, width_px)
    graphs = {name: _export_graph(name, specs[name], folder / graph_file(name, height_px, width_px)) for name in GRAPHS}
    return {"height_px": height_px, "width_px": width_px, "graphs": graphs}


def _export_graph(name: str, spec, path: Path) -> dict:
    """One graph exported with torch.onnx (dynamo) to ``path``, checked by onnx; -> its
    manifest entry."""
    import onnx
    import torch

    module, args, in_names, out_names, dynamic = spec
    with warnings.catch_warnings(), torch.no_grad():
        warnings.simplefilter("ignore")
        # a forward(*args) is one parameter to torch.export: its specs go as one tuple
        shapes = (dynamic,) if name in VARARGS_GRAPHS else dynamic
        torch.onnx.export(
            module,
            args,
            str(path),
            input_names=in_names,
            output_names=out_names,
            dynamic_shapes=shapes,
            opset_version=OPSET,
            dynamo=True,
            external_data=False,
            verbose=False,
        )
        outputs = module(*args)
    onnx.checker.check_model(str(path), full_check=True)
    outputs = outputs if isinstance(outputs, tuple) else (outputs,)
    out_dynamic = [{0: "views", 1: "thresholds"} if name == "thresholds" else {0: "views"}] * len(outputs)
    return {
        "file": path.name,
        "sha256": sha256_file(path),
        "inputs": _io(args, in_names, dynamic),
        "outputs": _io(outputs, out_names, out_dynamic),
    }


def _manifest(ckpt: dict, weights, sizes: list[dict]) -> dict:
    import onnx
    import torch

    from bittc_core.checkpoint import release_name

    cfg = ckpt["model_config"]
    return {
        "format": FORMAT,
        "precision": "float32",
        "config_name": ckpt["config_name"],
        "model_config": json.loads(json.dumps(asdict(cfg))),
        "weights": {"file": Path(weights).name, "sha256": sha256_file(weights), "release": release_name(ckpt)},
        "image": {
            "layout": "NCHW",
            "channels": "RGB",
            "range": [0.0, 1.0],
            "normalisation": "(x - 0.5) / 0.5, inside the graphs",
        },
        "frame_dt_s": cfg.frame_dt_s,
        "tau_range_s": [cfg.tau_min_s, cfg.tau_max_s],
        "eta_range": [
            cfg.tau_min_s / (cfg.tau_min_s + cfg.frame_dt_s),
            cfg.tau_max_s / (cfg.tau_max_s + cfg.frame_dt_s),
        ],
        "continuous": {"eta_min": cfg.cont_eta_min, "eta_max": cfg.cont_eta_max, "levels": cfg.cont_levels},
        "opset": OPSET,
        "sizes": sizes,
        "quantization": None,
        "exporter": {
            "torch": torch.__version__,
            "onnx": onnx.__version__,
            "created": datetime.date.today().isoformat(),
        },
    }


def _swap_in(tmp: Path, out: Path) -> None:
    """Replace ``out`` (absent, empty or an export folder) by ``tmp``."""
    old = None
    if out.exists():
        old = out.with_name(f".{out.name}.old")
        shutil.rmtree(old, ignore_errors=True)
        os.replace(out, old)
    os.replace(tmp, out)
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)
