"""`bittc export --onnx DIR`: the streaming network as ONNX graphs with a manifest."""

from __future__ import annotations

import argparse

from bittc_core.errors import CliError


def add_parser(sub) -> argparse.ArgumentParser:
    p = sub.add_parser(
        "export",
        help="export the network to ONNX (extractor, reference, thresholds, continuous)",
        description="Writes DIR/<graph>_<H>x<W>.onnx for the graphs extractor, reference, thresholds and "
        "continuous at every frame size (by default the default camera's wide view and fovea) and "
        "DIR/manifest.json (config, weights hash and release, the sizes with their input/output names, "
        "shapes and dtypes, image normalisation, frame_dt_s, trained eta range, opset). The thresholds "
        "graph takes the K thresholds (eta values) as a dynamic axis. Run it on onnxruntime with "
        "--backend onnxruntime --onnx DIR; each view runs the graphs of its size.",
    )
    p.add_argument(
        "--onnx", required=True, metavar="DIR", help="the folder to write (new, empty, or an export to replace)"
    )
    p.add_argument("--weights", default=None, help="checkpoint (default: the shipped weights)")
    p.add_argument(
        "--size",
        nargs="+",
        default=None,
        metavar="HxW",
        help="frame sizes [px] the graphs take, multiples of 3 (default: the default camera's wide view "
        "and fovea, 96x288 96x144)",
    )
    return p


def default_sizes() -> list[tuple[int, int]]:
    """(H, W) [px] of the default camera's views: the wide view and the fovea (the CLI's default zoom)."""
    from sim.camera import CameraConfig
    from sim.cli.common import DEFAULT_FOVEA, parse_fovea

    camera = CameraConfig(fovea_zoom=parse_fovea(DEFAULT_FOVEA))
    views = (camera.wide(), camera.fovea())
    return list(dict.fromkeys((v.height_px, v.width_px) for v in views))


def check_sizes(texts: list[str] | None) -> list[tuple[int, int]]:
    from sim.cli.common import check_frame_size, parse_size

    if texts is None:
        return default_sizes()
    sizes = []
    for text in texts:
        size = parse_size(text)
        check_frame_size(size, "bittc", f"--size {text}", hint="")
        if size in sizes:
            raise CliError(f"--size {text}: given twice")
        sizes.append(size)
    return sizes


def run(args) -> int:
    import time

    from bittc_core.checkpoint import DEFAULT_WEIGHTS
    from bittc_core.export.onnx_export import export_onnx

    sizes = check_sizes(args.size)
    weights = args.weights or str(DEFAULT_WEIGHTS)
    t0 = time.perf_counter()
    m = export_onnx(weights, args.onnx, sizes=sizes)  # a ConfigError names the file or value
    for size in m["sizes"]:
        for name, g in size["graphs"].items():
            ins = ", ".join(f"{i['name']} {i['shape']}" for i in g["inputs"])
            print(f"{name:<11} {g['file']:<28} in: {ins}")
    print(
        f"exported {weights} ({m['config_name']}, release {m['weights']['release']}) to {args.onnx} "
        f"at {', '.join(f'{s[0]}x{s[1]}' for s in sizes)} px (opset {m['opset']}) in {time.perf_counter() - t0:.0f} s"
    )
    return 0
