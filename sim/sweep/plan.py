"""What a sweep runs: its settings (stored as ``DIR/sweep.json``) and its list of runs.

A run is one scenario case, one controller, one fovea setting, one threshold count K,
one latency mode and one seed. Controllers without thresholds (``oracle``, ``none``, a
user's own) run once per latency mode with K = 0 and without a fovea. Seeds are
0 .. seeds - 1. The runs are listed in a fixed order (suite order of the cases, then
controller, fovea, K, latency mode, seed), which is the row order of ``results.csv``
whatever the order they finish in.
"""

from __future__ import annotations

import json
import re
from dataclasses import asdict, dataclass, field
from pathlib import Path

from bittc_core.errors import ConfigError

SETTINGS_FILE = "sweep.json"
MAX_SEEDS = 1000
NET_BACKENDS = ("torch", "onnxruntime")


@dataclass(frozen=True)
class SweepSettings:
    """Everything that decides a sweep's results (the output folder and the worker count
    do not)."""

    suites: tuple[str, ...]  # suite names (``scenarios.SUITES``), bundled names or YAML files
    controllers: tuple[str, ...]  # registered names or module:Class
    num_alphas: tuple[int, ...] = (1, 2, 4, 8, 16)  # K values for the geofence controllers
    latencies: tuple[str, ...] = ("measured",)  # latency modes (``sim.latency.parse_latency``)
    seeds: int = 1  # seeds 0 .. seeds - 1
    weights: str | None = None  # geofence: network weights (None: the shipped ones)
    frame_stride: int | None = None  # geofence/flow: None for the controller's default
    video_cases: tuple[str, ...] = ()  # cases whose runs also write camera.mp4
    timeline_case: str | None = None  # the case of the timeline plot (None: the first threat)
    net_backend: str = "torch"  # geofence: the network on torch or onnxruntime
    onnx: str | None = None  # with net_backend "onnxruntime": the export folder
    foveas: tuple[float | None, ...] = (None,)  # geofence/flow: fovea zooms (None: the wide view alone)

    def to_json(self) -> str:
        return json.dumps(asdict(self), indent=2, sort_keys=True) + "\n"

    @classmethod
    def from_json(cls, text: str, where: str) -> SweepSettings:
        try:
            d = json.loads(text)
            return cls(**{k: tuple(v) if isinstance(v, list) else v for k, v in d.items()})
        except (ValueError, TypeError) as e:
            raise ConfigError(f"{where}: not a sweep settings file ({e})") from None


@dataclass(frozen=True)
class RunSpec:
    """One run of a sweep; ``run_id`` names its folder under ``DIR/runs/``."""

    case: str
    controller: str
    num_alphas: int  # 0 for controllers without thresholds
    latency: str
    seed: int
    index: int = field(default=0, compare=False)  # position in the plan
    fovea_zoom: float | None = None  # None: the wide view alone

    @property
    def config_id(self) -> str:
        """The controller x fovea x K x latency configuration, e.g. ``geofence-K4-fixed_50``
        or ``geofence-F4-K4-measured``."""
        f = f"-F{self.fovea_zoom:g}" if self.fovea_zoom is not None else ""
        k = f"-K{self.num_alphas}" if self.num_alphas else ""
        return f"{_slug(self.controller)}{_slug(f)}{k}-{_slug(self.latency)}"

    @property
    def run_id(self) -> str:
        return f"{self.config_id}/{self.case}-s{self.seed}"


def _slug(text: str) -> str:
    """A folder-safe spelling: every run of characters other than letters, digits, _ and -
    becomes one _ (``fixed:50`` -> ``fixed_50``, ``profile:my/dev.yaml`` -> ``profile_my_dev_yaml``)."""
    return re.sub(r"[^A-Za-z0-9_-]+", "_", text)


def check_settings(s: SweepSettings) -> list:
    """Validate every setting before any run starts; -> the cases, in suite order
    (a case named by two suites runs once). Errors name the bad value."""
    import controllers
    from sim.latency import parse_latency

    if not s.suites:
        raise ConfigError("suites: name at least one suite, scenario or file")
    if not s.controllers:
        raise ConfigError("controllers: name at least one controller")
    from controllers.geofence import MAX_THRESHOLDS

    if not s.num_alphas:
        raise ConfigError("num_alphas: give at least one K")
    for k in s.num_alphas:
        if isinstance(k, bool) or not isinstance(k, int) or not 1 <= k <= MAX_THRESHOLDS:
            raise ConfigError(f"num_alphas: K = {k!r} must be an integer in [1, {MAX_THRESHOLDS}]")
    if not s.latencies:
        raise ConfigError("latencies: give at least one latency mode")
    for text in s.latencies:
        parse_latency(text)
    if isinstance(s.seeds, bool) or not isinstance(s.seeds, int) or not 1 <= s.seeds <= MAX_SEEDS:
        raise ConfigError(f"seeds: {s.seeds!r} must be an integer in [1, {MAX_SEEDS}]")
    for name in s.controllers:
        if name not in controllers.REGISTRY and ":" not in name:
            raise ConfigError(
                f"unknown controller {name!r}; known: {', '.join(controllers.REGISTRY)} (or module:Class)"
            )
    if s.weights is not None and "geofence" not in s.controllers:
        raise ConfigError("weights: apply to the geofence controller, which the sweep does not run")
    if s.weights is not None and not Path(s.weights).is_file():
        raise ConfigError(f"weights: no file {s.weights!r}")
    _check_net_backend(s)
    if s.frame_stride is not None:
        from controllers.geofence import check_frame_stride

        try:
            check_frame_stride(s.frame_stride)
        except ConfigError as e:
            raise ConfigError(f"frame_stride: {e}") from None
    from sim.camera import check_fovea_zoom

    if not s.foveas:
        raise ConfigError("foveas: give at least one fovea setting (None for the wide view alone)")
    for z in s.foveas:
        try:
            check_fovea_zoom(z)
        except ValueError as e:
            raise ConfigError(f"foveas: {e}") from None
    cases = suite_cases(s.suites)
    names = {c.name for c in cases}
    for name in s.video_cases + ((s.timeline_case,) if s.timeline_case else ()):
        if name not in names:
            raise ConfigError(f"case {name!r} is not in the sweep's suites")
    return cases


def _check_net_backend(s: SweepSettings) -> None:
    if s.net_backend not in NET_BACKENDS:
        raise ConfigError(f"net_backend: {s.net_backend!r} must be one of {', '.join(NET_BACKENDS)}")
    if s.net_backend == "torch":
        if s.onnx is not None:
            raise ConfigError("onnx: an export folder applies to the onnxruntime network backend")
        return
    if "geofence" not in s.controllers:
        raise ConfigError(
            "net_backend: onnxruntime runs the geofence controller's network, which the sweep does not run"
        )
    if s.onnx is None:
        raise ConfigError("onnx: the onnxruntime network backend needs an export folder (`bittc export` makes one)")
    from bittc_core.checkpoint import DEFAULT_WEIGHTS, load_checkpoint
    from bittc_core.estimator.onnx import require_onnxruntime
    from bittc_core.export.graphs import GRAPHS
    from bittc_core.export.manifest import check_matches_checkpoint, read_manifest

    require_onnxruntime()
    weights = s.weights or DEFAULT_WEIGHTS
    check_matches_checkpoint(read_manifest(s.onnx, graphs=GRAPHS), s.onnx, load_checkpoint(weights), weights)


def suite_cases(suites: tuple[str, ...]) -> list:
    """The cases of ``suites`` in order; a case named by two suites comes once."""
    import scenarios

    cases, seen = [], set()
    for suite in suites:
        for case in scenarios.resolve_suite(suite):
            if case.name not in seen:
                seen.add(case.name)
                cases.append(case)
    return cases


def plan_runs(s: SweepSettings, cases: list) -> list[RunSpec]:
    import controllers

    runs = []
    for case in cases:
        for name in s.controllers:
            est = name in controllers.ESTIMATOR_CONTROLLERS
            for zoom in s.foveas if est else (None,):
                for k in s.num_alphas if est else (0,):
                    for latency in s.latencies:
                        for seed in range(s.seeds):
                            runs.append(RunSpec(case.name, name, k, latency, seed, len(runs), zoom))
    return runs
