"""Where the tracker reads a region's edges (``controllers.evidence``,
``controllers.path_prediction``, ``controllers.tracker``), on hand-made masks: the ground
under a walker whose leg swings past its upper body, and the inner edge of a region whose
lower rows only a smaller fence counts."""

import math

import numpy as np

from controllers.evidence import Blob, contact_depth
from controllers.path_prediction import PathPrediction
from controllers.track import Obs, Track
from controllers.tracker import BlobTracker, TrackerConfig
from tests.geofence_maps import CAL

H, W = 40, 60
DEPTH = np.linspace(100.0, 2.0, H)  # [m] a stand-in ground depth per row, nearer lower down


def test_the_ground_beside_a_swinging_leg_is_not_where_a_walker_stands():
    fenced = np.zeros((H, W), dtype=bool)
    fenced[10:21, 20:24] = True  # the upper body, the region's columns
    fenced[21:29, 25] = True  # a leg swung one column past them
    fenced[29:] = True  # the road in front of the walker: nearer, inside the fence
    body = np.zeros_like(fenced)
    body[10:21, 20:24] = True
    # read in the body's columns alone, the row beside the leg is free: the ground there
    # lies beyond the walker, and its depth would throw the walker's fitted motion
    assert contact_depth(fenced, body, 20, 23, DEPTH) == DEPTH[21]
    # widened past the leg, no row is free down to the image's bottom
    assert contact_depth(fenced, body, 20, 23, DEPTH, pad_px=2) is None
    # an oncoming car: the road under it lies outside the fence, widened or not
    fenced[29:] = False
    assert contact_depth(fenced, body, 20, 23, DEPTH, pad_px=2) == DEPTH[29]


def _region_left_of_centre():
    """A region left of the image centre: an upright object in the larger fence, and a strip
    along the lowest rows that only the smaller fence counts, reaching 10 px further in."""
    larger = np.zeros((CAL.height_px, CAL.width_px), dtype=bool)
    larger[20:40, 60:80] = True
    smaller = np.zeros_like(larger)
    smaller[40:43, 60:90] = True
    mask = larger | smaller
    return Blob(mask, 60.0, 89.0, 2.8), [smaller, larger]


def test_the_inner_edge_is_read_on_the_largest_fence_that_holds_the_region():
    blob, parts = _region_left_of_centre()
    read = PathPrediction._largest_fence_edge(blob, parts, CAL)
    assert read.inner_px == 79.0 and (read.u_left, read.u_right) == (60.0, 89.0)
    obs = Obs(0.0, read.u_left, read.u_right, 2.8, None, 10.0, (0.0, 0.0, 0.0), read.inner_px)
    assert math.isclose(obs.inner_bearing(CAL), (79.0 - CAL.cx_px) / CAL.fx_px)
    # without it, the strip's end is the inner edge
    obs.inner_px = None
    assert math.isclose(obs.inner_bearing(CAL), (89.0 - CAL.cx_px) / CAL.fx_px)
    # a region across the centre keeps its extent: the corridor rule judges it
    wide = Blob(blob.mask, 60.0, CAL.cx_px + 5, 2.8)
    assert PathPrediction._largest_fence_edge(wide, parts, CAL).inner_px is None


def _closing(columns, tol_px_per_s: float, width_px: int = 5) -> bool:
    cfg = TrackerConfig(bearing_tol_px_per_s=tol_px_per_s, corridor_allowance=False)
    tracker = BlobTracker(cfg, CAL)
    obs = [Obs(0.1 * k, u, u + width_px, 2.8, None, 10.0, (0.0, 0.0, 0.0)) for k, u in enumerate(columns)]
    track = Track(obs=obs)
    return tracker.closing_in(track, track.contact_time_s())


def test_a_bearing_that_flickers_by_a_pixel_still_holds_within_the_tolerance():
    u = CAL.cx_px + 20  # right of the centre: the inner edge is the left one
    flicker = [u, u, u + 1, u, u, u + 1]  # 1.1 px/s out, fitted over 0.5 s
    assert not _closing(flicker, 0.0)
    assert _closing(flicker, 2.0)
    # a standing object beside the path moves out by a pixel a job: 10 px/s
    assert not _closing([u + k for k in range(6)], 2.0)
    # a region wider than a road user (28 m away, 60 px are 9 m) must hold exactly
    assert not _closing(flicker, 2.0, width_px=60)
