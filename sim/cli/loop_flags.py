"""Controller and latency flags shared by `bittc run` and `bittc suite`."""

from __future__ import annotations

import argparse

from bittc_core.errors import CliError, ConfigError


def add_controller_flags(p: argparse.ArgumentParser, default: str | None = None) -> None:
    import controllers
    from controllers.geofence import DEFAULT_FOVEA_FENCES_FROM_S

    p.add_argument(
        "--controller",
        required=default is None,
        default=default,
        help=f"{', '.join(controllers.REGISTRY)}, or module:Class for your own Controller subclass"
        + (f" (default {default})" if default else ""),
    )
    g = p.add_mutually_exclusive_group()
    g.add_argument(
        "--num-alphas",
        type=int,
        default=None,
        metavar="K",
        help="geofence/flow: K thresholds, uniform in log TTC over 0.8-2.8 s (K = 1: 1.5 s; default 4)",
    )
    g.add_argument(
        "--ttc-thresholds",
        type=float,
        nargs="+",
        default=None,
        metavar="S",
        help="geofence/flow: explicit camera-plane TTC thresholds [s], any order",
    )
    p.add_argument(
        "--latency",
        default=None,
        metavar="MODE",
        help="measured, fixed:MS, profile:NAME (`bittc profiles`) or profile:FILE (`bittc profile`); "
        "default measured for camera controllers, fixed:0 otherwise",
    )
    p.add_argument("--weights", default=None, help="geofence: network weights (default: the shipped ones)")
    p.add_argument(
        "--frame-stride",
        type=int,
        default=None,
        metavar="N",
        help="geofence/flow: pair each frame with the one N frames before (default 3)",
    )
    p.add_argument(
        "--fovea-fences-from",
        type=float,
        default=None,
        metavar="S",
        help="geofence/flow with a fovea: fences below S seconds run on the wide view only "
        f"(default {DEFAULT_FOVEA_FENCES_FROM_S:g}; 0: all in both)",
    )
    p.add_argument(
        "--road-edge-rows",
        type=int,
        default=None,
        metavar="N",
        help="geofence/flow: count a fence's pixels only more than N rows above the road's fence edge "
        "as the estimator draws it (for networks that fence the road past its static depth; default off)",
    )
    p.add_argument(
        "--turn-across",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="geofence/flow: the tracker's rules for a turn across an oncoming car's path (docs/vru.md; default on)",
    )
    p.add_argument(
        "--oncoming",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="geofence/flow: with the turn rules, the tracker's rules for oncoming traffic (docs/vru.md; default on)",
    )
    p.add_argument(
        "--fovea-short-pair",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="geofence/flow with a fovea: also read the fovea's smallest fence on the pair one frame apart, "
        "where a crossing road user moves a third as far (docs/vru.md; costs a threshold a job; default off)",
    )
    from sim.cli.common import add_backend_flags

    add_backend_flags(p)


def controller_from_args(args, camera):
    """-> (controller, latency mode), every flag checked and the controller reset once with
    this camera (so a frame interval the weights were not trained for is refused before
    anything is written)."""
    import controllers
    from controllers.base import Calibration
    from controllers.geofence import check_thresholds, default_thresholds
    from sim.latency import parse_latency
    from sim.vehicles import EGO_SIZE_M

    name = args.controller
    settings = {}
    takes_fences = name in controllers.ESTIMATOR_CONTROLLERS
    try:
        if args.num_alphas is not None:
            settings["thresholds_s"] = default_thresholds(args.num_alphas)
        if args.ttc_thresholds is not None:
            settings["thresholds_s"] = check_thresholds(args.ttc_thresholds)
    except ConfigError as e:
        flag = "--num-alphas" if args.num_alphas is not None else "--ttc-thresholds"
        raise CliError(f"{flag}: {e}") from None
    if args.frame_stride is not None:
        from controllers.geofence import check_frame_stride

        try:
            settings["frame_stride"] = check_frame_stride(args.frame_stride)
        except ConfigError as e:
            raise CliError(f"--frame-stride: {e}") from None
    if args.fovea_fences_from is not None:
        settings["fovea_fences_from_s"] = args.fovea_fences_from
    if args.road_edge_rows is not None:
        if args.road_edge_rows < 0:
            raise CliError(f"--road-edge-rows {args.road_edge_rows}: must be an integer >= 0")
        settings["road_edge_rows"] = args.road_edge_rows
    if args.turn_across is not None:
        settings["turn_across"] = args.turn_across
    if args.oncoming is not None:
        settings["oncoming"] = args.oncoming
    if args.fovea_short_pair is not None:
        settings["fovea_short_pair"] = args.fovea_short_pair
    if args.weights is not None:
        if name != "geofence":
            raise CliError(f"--weights applies to the geofence controller, not {name!r}")
        settings["weights"] = args.weights
    if args.backend != "torch" or args.onnx is not None:
        from sim.cli.common import backend_kwargs

        if name != "geofence":
            raise CliError(f"--backend / --onnx apply to the geofence controller, not {name!r}")
        settings.update(backend_kwargs(args))
    if settings and name in controllers.REGISTRY and not takes_fences:
        raise CliError(
            "--num-alphas / --ttc-thresholds / --frame-stride / --fovea-fences-from / --road-edge-rows / "
            f"--[no-]fovea-short-pair / --[no-]turn-across / --[no-]oncoming apply to "
            f"{' and '.join(controllers.ESTIMATOR_CONTROLLERS)}, not {name!r}"
        )
    try:
        latency = parse_latency(args.latency) if args.latency is not None else None
    except ConfigError as e:
        raise CliError(f"--latency: {e}") from None
    try:
        ctrl = controllers.make(name, **settings)
    except ConfigError as e:
        raise CliError(f"--controller {name}: {e}") from None
    try:
        ctrl.reset(Calibration.from_camera(camera, EGO_SIZE_M))
    except ConfigError as e:
        raise CliError(f"--fps / --frame-stride / --fovea-fences-from: {e}") from None
    if latency is None:
        from sim.runner import default_latency

        latency = default_latency(ctrl)
    return ctrl, latency
