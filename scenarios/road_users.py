"""Road-user targets of the scenarios, as plain data (no simulator imports): kinds, the
Euro NCAP targets' heights and contact footprints [m]. Bodies are built by ``sim.vru``.

Footprint: (length along the direction of travel, width across it) [m].
"""

from __future__ import annotations

ADULT_HEIGHT_M = 1.8  # [m] Euro NCAP pedestrian target, adult (EPTa)
CHILD_HEIGHT_M = 1.15  # [m] Euro NCAP pedestrian target, child (EPTc)
CYCLIST_HEIGHT_M = 1.8  # [m] the rider of the bicyclist target (EBTa), standing
BICYCLE_LENGTH_M = 1.9  # [m]
BICYCLE_WIDTH_M = 0.6  # [m] handlebar width
VRU_KINDS = ("adult", "child", "cyclist")
DEFAULT_HEIGHT_M = {"adult": ADULT_HEIGHT_M, "child": CHILD_HEIGHT_M, "cyclist": CYCLIST_HEIGHT_M}
#: the class of each kind in ground truth and datasets
VRU_CLASS = {"adult": "pedestrian", "child": "pedestrian", "cyclist": "cyclist"}


def footprint_m(kind: str, height_m: float) -> tuple[float, float]:
    """(length, width) [m] of a road user's contact footprint; a pedestrian's scales with height."""
    if kind == "cyclist":
        return BICYCLE_LENGTH_M, BICYCLE_WIDTH_M
    return 0.3 * height_m / ADULT_HEIGHT_M, 0.5 * height_m / ADULT_HEIGHT_M
