"""`bittc export --onnx DIR [--int8]`: the streaming network as ONNX graphs with a manifest.

With --int8 the graphs are quantized (``bittc_core.export.quantize``), calibrated on frame
pairs rendered from ``CALIBRATION_CASES`` and checked on pairs of ``HELD_OUT_CASES``
(other scenes), in every exported size, at the geofence controller's frame stride; the
parity is measured at the controller's default fences (K = ``PARITY_K``).
"""

from __future__ import annotations

import argparse

from bittc_core.errors import CliError

CALIBRATION_CASES = ("CCRs-50", "CCRm-50", "cut-in", "benign-oncoming")
HELD_OUT_CASES = ("CCRs-30", "CCRb-12m-6mps2", "near-merge-45-15m", "benign-parked-truck", "head-on")
PAIRS_PER_CASE = 6  # pairs per case and size, spread evenly over the case's run
RENDER_SEED = 0
PARITY_K = 4  # the parity's fences: the geofence controller's default K thresholds


def add_parser(sub) -> argparse.ArgumentParser:
    p = sub.add_parser(
        "export",
        help="export the network to ONNX (extractor, reference, thresholds, continuous)",
        description="Writes DIR/<graph>_<H>x<W>.onnx for the graphs extractor, reference, thresholds and "
        "continuous at every frame size (by default the default camera's wide view and fovea) and "
        "DIR/manifest.json (config, weights hash and release, the sizes with their input/output names, "
        "shapes and dtypes, image normalisation, frame_dt_s, trained eta range, opset). The thresholds "
        "graph takes the K thresholds (eta values) as a dynamic axis. Run it on onnxruntime with "
        "--backend onnxruntime --onnx DIR; each view runs the graphs of its size. With --int8 the "
        "per-threshold graphs are quantized to int8 (onnxruntime static quantization, calibrated on "
        "rendered scenario frames) and the share of fence decisions that change against float32 on "
        "other scenes is printed and written to the manifest.",
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
    p.add_argument(
        "--int8",
        action="store_true",
        help=f"quantize to int8, calibrated on {PAIRS_PER_CASE} rendered pairs of each of "
        f"{', '.join(CALIBRATION_CASES)}, checked on {', '.join(HELD_OUT_CASES)}",
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


def int8_settings(weights: str, sizes: list[tuple[int, int]]):
    """The calibration and held-out pairs rendered in every size, and the parity's fences."""
    from types import SimpleNamespace

    import scenarios
    from bittc_core.checkpoint import load_checkpoint
    from bittc_core.export.quantize import FramePairs, Int8Settings
    from controllers.geofence import DEFAULT_FRAME_STRIDE, default_thresholds, estimator_thresholds
    from sim.camera import CameraConfig
    from sim.cli.common import DEFAULT_FOVEA, parse_fovea
    from sim.frame_pairs import pairs_of_sizes

    zoom = parse_fovea(DEFAULT_FOVEA)

    def frames(names) -> FramePairs:
        cases = [c for n in names for c in scenarios.resolve_suite(n)[:1]]
        by_size = pairs_of_sizes(cases, sizes, zoom, RENDER_SEED, PAIRS_PER_CASE, DEFAULT_FRAME_STRIDE)
        source = (
            f"{PAIRS_PER_CASE} pairs (stride {DEFAULT_FRAME_STRIDE}) of each of {', '.join(names)}, seed "
            f"{RENDER_SEED}, open loop; wide views and fovea x{zoom:g} of the default camera"
        )
        return FramePairs(tuple(p for pairs in by_size.values() for p in pairs), source)

    cfg = load_checkpoint(weights, map_location="cpu")["model_config"]
    net = SimpleNamespace(dt_s=cfg.frame_dt_s, tau_range_s=(cfg.tau_min_s, cfg.tau_max_s))
    thr = estimator_thresholds(net, default_thresholds(PARITY_K), CameraConfig().dt_s, DEFAULT_FRAME_STRIDE)
    return Int8Settings(frames(CALIBRATION_CASES), frames(HELD_OUT_CASES), tuple(float(t) for t in thr))


def print_parity(m: dict, sizes: list[tuple[int, int]]) -> None:
    from controllers.geofence import default_thresholds

    parity = m["quantization"]["parity"]
    names = dict(zip(map(tuple, default_sizes()), ("wide", "fovea")))
    fences = default_thresholds(PARITY_K)
    print(
        f"int8 against float32 on {sum(parity['pairs'].values())} held-out pairs: share of pixels whose fence "
        f"decision (p > 0.5) changed, at the geofence controller's default fences [s]"
    )
    print(f"{'size':<12}{'view':<7}{'pairs':>6}" + "".join(f"{t:>9g}" for t in fences))
    for size in sizes:
        key = f"{size[0]}x{size[1]}"
        row = parity["decision_changed"][key].values()
        print(f"{key:<12}{names.get(size, ''):<7}{parity['pairs'][key]:>6}" + "".join(f"{c:>9.2%}" for c in row))
    worst, target = parity["decision_changed_max"], parity["target"]
    verdict = "within" if worst <= target else "OVER"
    print(f"largest {worst:.2%}: {verdict} the {target:.0%} target")


def run(args) -> int:
    import time

    from bittc_core.checkpoint import DEFAULT_WEIGHTS
    from bittc_core.export.onnx_export import export_onnx

    sizes = check_sizes(args.size)
    weights = args.weights or str(DEFAULT_WEIGHTS)
    t0 = time.perf_counter()
    int8 = None
    if args.int8:
        int8 = int8_settings(weights, sizes)
        print(f"rendered the calibration and held-out frame pairs in {time.perf_counter() - t0:.0f} s")
    m = export_onnx(weights, args.onnx, sizes=sizes, int8=int8)  # a ConfigError names the file or value
    for size in m["sizes"]:
        for name, g in size["graphs"].items():
            ins = ", ".join(f"{i['name']} {i['shape']}" for i in g["inputs"])
            print(f"{name:<11} {g['file']:<28} {g.get('precision', m['precision']):<8} in: {ins}")
    print(
        f"exported {weights} ({m['config_name']}, release {m['weights']['release']}) to {args.onnx} "
        f"at {', '.join(f'{s[0]}x{s[1]}' for s in sizes)} px, {m['precision']} (opset {m['opset']}) "
        f"in {time.perf_counter() - t0:.0f} s"
    )
    if args.int8:
        print_parity(m, sizes)
    return 0
