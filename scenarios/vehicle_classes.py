"""Vehicle classes of the scenarios and their size ranges [m], as plain data (no simulator
imports): names validated by ``scenarios.spec``, bodies built by ``sim.vehicles``.

kind -> ((length min, max), (width min, max), (height min, max)) [m]."""

from __future__ import annotations

VEHICLE_CLASSES: dict[str, tuple[tuple[float, float], tuple[float, float], tuple[float, float]]] = {
    "car": ((4.0, 4.9), (1.7, 1.9), (1.4, 1.6)),
    "gvt": ((4.02, 4.02), (1.71, 1.71), (1.5, 1.5)),  # Euro NCAP global vehicle target
    "van": ((4.8, 5.5), (1.9, 2.05), (1.9, 2.4)),
    "truck": ((7.0, 10.0), (2.4, 2.55), (3.0, 3.6)),
}

#: the ego's (length, width, height) [m]; Euro NCAP files use a 1.815 m ego width
EGO_SIZE_M = (4.6, 1.815, 1.45)
