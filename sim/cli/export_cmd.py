"""`bittc export --onnx DIR`: the streaming network as ONNX graphs with a manifest."""

from __future__ import annotations

import argparse


def add_parser(sub) -> argparse.ArgumentParser:
    p = sub.add_parser(
        "export",
        help="export the network to ONNX (extractor, reference, thresholds, continuous)",
        description="Writes DIR/{extractor,reference,thresholds,continuous}.onnx and DIR/manifest.json "
        "(config, weights hash and release, input/output names, shapes and dtypes, image "
        "normalisation, frame_dt_s, trained eta range, opset). The thresholds graph takes the K "
        "thresholds (eta values) as a dynamic axis. Run it on onnxruntime with --backend "
        "onnxruntime --onnx DIR.",
    )
    p.add_argument(
        "--onnx", required=True, metavar="DIR", help="the folder to write (new, empty, or an export to replace)"
    )
    p.add_argument("--weights", default=None, help="checkpoint (default: the shipped weights)")
    p.add_argument(
        "--size", default="96x288", help="frame size HxW [px] the graphs take, multiples of 3 (default 96x288)"
    )
    return p


def run(args) -> int:
    import time

    from bittc_core.checkpoint import DEFAULT_WEIGHTS
    from bittc_core.export.onnx_export import export_onnx
    from sim.cli.common import check_frame_size, parse_size

    h, w = parse_size(args.size)
    check_frame_size((h, w), "bittc", f"--size {args.size}", hint="")
    weights = args.weights or str(DEFAULT_WEIGHTS)
    t0 = time.perf_counter()
    m = export_onnx(weights, args.onnx, height_px=h, width_px=w)  # a ConfigError names the file or value
    for name, g in m["graphs"].items():
        ins = ", ".join(f"{i['name']} {i['shape']}" for i in g["inputs"])
        print(f"{name:<11} {g['file']:<16} in: {ins}")
    print(
        f"exported {weights} ({m['config_name']}, release {m['weights']['release']}) to {args.onnx} "
        f"(opset {m['opset']}) in {time.perf_counter() - t0:.0f} s"
    )
    return 0
