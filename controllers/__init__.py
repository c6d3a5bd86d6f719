"""Braking policies: observation -> brake command. Registry by name."""

from __future__ import annotations

from typing import Callable

from controllers.base import BrakeCommand, Controller, Observation
from controllers.none import NoController
from controllers.oracle import OracleConfig, OracleController

REGISTRY: dict[str, Callable[[], Controller]] = {
    "none": NoController,
    "oracle": OracleController,
}


def make(name: str) -> Controller:
    if name not in REGISTRY:
        raise ValueError(f"unknown controller {name!r}; known: {', '.join(REGISTRY)}")
    return REGISTRY[name]()


__all__ = ["BrakeCommand", "Controller", "Observation", "OracleConfig", "OracleController", "NoController", "REGISTRY", "make"]
