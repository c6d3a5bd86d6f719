"""Braking policies: observation -> brake command.

Controllers are built from a registry of string entry points (as Gymnasium registers
envs), so that listing them never imports torch: ``make("geofence", thresholds_s=(1.0,
2.0))``. ``make("my_module:MyClass")`` (an importable module) or
``make("path/to/file.py:MyClass")`` loads a user's own ``Controller`` subclass.
"""

from __future__ import annotations

import importlib
import importlib.util
import inspect
from pathlib import Path
from typing import Any

from bittc_core.errors import ConfigError
from controllers.base import BrakeCommand, Calibration, Controller, GeofenceView, Observation
from controllers.none import NoController
from controllers.oracle import OracleConfig, OracleController

#: name -> "module:callable" building the controller; settings are keyword arguments
REGISTRY: dict[str, str] = {
    "none": "controllers.none:NoController",
    "oracle": "controllers.oracle:OracleController",
    "geofence": "controllers.geofence_factory:make_geofence",
    "flow": "controllers.geofence_factory:make_flow",
    # the geofence policy on exact fences from the per-pixel ground truth: an upper bound
    "geofence-exact": "controllers.geofence_factory:make_geofence_exact",
}
#: controllers whose decisions come from an estimator's geofences (they take thresholds)
ESTIMATOR_CONTROLLERS = ("geofence", "flow", "geofence-exact")


def _load(entry: str, what: str):
    """'package.module:attr' (importable) or 'path/to/file.py:attr' -> the attribute."""
    module_name, sep, attr = entry.rpartition(":")
    if not sep or not module_name or not attr:
        raise ConfigError(
            f"controller {what!r}: expected a registered name ({', '.join(REGISTRY)}), module:Class "
            "or path/to/file.py:Class"
        )
    if module_name.endswith(".py"):
        path = Path(module_name)
        if not path.is_file():
            raise ConfigError(f"controller {what!r}: no file {module_name!r}")
        spec = importlib.util.spec_from_file_location(f"bittc_user_controller_{path.stem}", path)
        module = importlib.util.module_from_spec(spec)
        try:
            spec.loader.exec_module(module)
        except Exception as e:
            raise ConfigError(f"controller {what!r}: cannot load {module_name!r} ({type(e).__name__}: {e})") from None
    else:
        try:
            module = importlib.import_module(module_name)
        except ImportError as e:
            raise ConfigError(f"controller {what!r}: cannot import module {module_name!r} ({e})") from None
    try:
        return getattr(module, attr)
    except AttributeError:
        raise ConfigError(f"controller {what!r}: module {module_name!r} has no attribute {attr!r}") from None


def make(name: str, **settings: Any) -> Controller:
    """Build a registered controller, or a ``module:Class`` subclass of ``Controller``.

    ``settings`` are keyword arguments of its builder; one it does not take is refused."""
    entry = REGISTRY.get(name)
    if entry is None and ":" not in name:
        raise ConfigError(f"unknown controller {name!r}; known: {', '.join(REGISTRY)} (or module:Class)")
    factory = _load(entry or name, name)
    if entry is None and not (inspect.isclass(factory) and issubclass(factory, Controller)):
        raise ConfigError(f"controller {name!r}: {factory!r} is not a subclass of controllers.Controller")
    params = inspect.signature(factory).parameters
    takes_any = any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values())
    unknown = [k for k in settings if k not in params and not takes_any]
    if unknown:
        raise ConfigError(f"controller {name!r} takes no setting {unknown[0]!r}")
    ctrl = factory(**settings)
    if not isinstance(ctrl, Controller):
        raise ConfigError(f"controller {name!r}: built a {type(ctrl).__name__}, not a controllers.Controller")
    return ctrl


__all__ = [
    "BrakeCommand",
    "Calibration",
    "Controller",
    "GeofenceView",
    "Observation",
    "OracleConfig",
    "OracleController",
    "NoController",
    "REGISTRY",
    "ESTIMATOR_CONTROLLERS",
    "make",
]
