"""The tracker's settings (``controllers.tracker``): association, motion fit, prediction,
the bearing test and its allowances, the hold, and where a region's edges are read. Units
on every field; defaults as measured in docs/vru.md."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class TrackerConfig:
    enabled: bool = True  # False: only the corridor now counts (the straight-road controller)
    # the views it runs in: the wide view sees a road user stepping out near the ego; the fovea's
    # regions are far targets (60 m at 80 km/h) whose coarse depth turns fence noise into motion
    views: tuple[str, ...] = ("wide",)
    gate_frac: float = 0.6  # [-] association gate, share of the wider region's width
    min_gate_px: float = 4.0  # [px]
    min_hits: int = 3  # [jobs] regions before a track predicts
    window: int = 6  # [jobs] regions in the motion fit
    max_missed: int = 2  # [jobs]
    margin_m: float = 0.25  # [m] beyond the ego's half width, each side
    target_half_length_m: float = 0.4  # [m] a target's half extent along the ego's heading
    horizon_pad_s: float = 0.3  # [s] predict this far past the track's TTC
    step_s: float = 0.05  # [s]
    min_ttc_s: float = 0.2  # [s] the smallest TTC a depth is placed at
    max_speed_mps: float = 15.0  # [m/s] a faster fitted ground speed is a bad association
    min_speed_mps: float = 0.8  # [m/s] a slower target is standing: the corridor rule judges it
    all_fences: bool = True  # regions of every fence where it is judged, not only the largest's
    # The two levers below are off by default: each avoids more road users and raises the
    # false alarms over the scenery seeds (docs/vru.md, "Levers").
    # a target spans its region's width (unbounded past a cut image side); off: its inner edge
    extent: bool = False
    # a region cut by the image's side predicts by its inner edge (its outer edge moves with
    # the cut); off: it predicts nothing
    cut_regions: bool = False
    # a road user's bearing test lets its inner edge move out as fast as one that meets the
    # camera plane inside the corridor (a pedestrian met at 25 % of the ego's width); off: it
    # must come in or hold
    corridor_allowance: bool = True
    # [px/s] a bearing that moves out no faster than this, in the view's own pixels, holds:
    # on a collision course the inner edge holds its column, and one pixel's flicker over
    # the window tips a fitted slope either way (the fovea's check sees 4x finer)
    bearing_tol_px_per_s: float = 1.0
    # [m] a region spans at least this height at the static depth of its fence: the road's
    # own fence, running past a fence's counted rows, leaves strips a few rows tall
    min_height_m: float = 0.5
    # [jobs] a track predicted into the path counts for this many more jobs in which the
    # prediction fails: a crossing cyclist's few pixels of edge swing its fit from job to job
    hold_jobs: int = 2
    # [m] a region this narrow at its fence's static depth is a road user's: only such a track
    # is held, and only its bearing test has the tolerance and the corridor allowance (a long
    # structure cut at a fence's static depth holds its bearing exactly). A child or cyclist
    # stepping out is one region with the parked car's end beside it: 3.8 m in CBNAO-50-40
    road_user_width_m: float = 4.5
    # [rows] parts one above the other with at most this many rows between them are one region:
    # a road user's upper body counted in a larger fence, its legs in a smaller one
    join_rows: int = 3
    # a region's inner edge is read on the pixels of the largest fence that holds part of it:
    # a smaller fence's counted rows reach lower, where a kerb or verge line crosses its
    # lowest row at a column that holds still (a collision course to the bearing test)
    edge_from_largest: bool = True
    # [m] the ground under a region is read this far beside it too, at its fence's static
    # depth: a walker's swinging leg reaches past the columns of its upper body and would
    # leave the ground beside it, further away, as the first free row
    contact_pad_m: float = 0.5
    # [px per row] a region whose inner edge slants outwards faster, row by row down, lies on
    # the ground: a strip of verge or road that the network fenced along a fence's boundary
    max_slant_px_per_row: float = 0.5
    # views whose tracks check the bearing test of the predicting views' tracks at the same
    # bearing (within check_tol_px of the predicting view): the fovea sees it 4x finer
    check_views: tuple[str, ...] = ("fovea",)
    check_tol_px: float = 2.0
    # predict also with a camera that has none of the (non-empty) check views, no fovea; off:
    # such a camera's tracker predicts nothing, since the wide view alone reads a parked
    # truck's far corner as a collision course (benign-parked-truck at K = 4)
    predict_unchecked: bool = False
    # the rules that let a turn across an oncoming car's path brake on the yaw rate alone
    # (docs/vru.md, "A turn across the path on the yaw rate alone"): a region counts also
    # where it does not reach a fence's lowest counted rows (it floats); a track keeps the
    # side it came from when its region crosses the image centre; a region's height is
    # judged at the depth of the ground under it where that lies beyond the fence's static
    # depth; association takes the ego's rotation out; a predicted region counts without
    # reaching the lowest counted rows if it is as tall and as big as the largest fence
    # asks. Off: the straight-road tracker of earlier releases
    turn_across: bool = True
    # [m/s] with ``turn_across``, a region that does not reach a fence's lowest counted
    # rows (it floats: an oncoming car whose road shows beneath it) predicts only when it
    # comes towards the ego at least this fast along the ego's heading when its track
    # began, and then along that heading only (oncoming traffic keeps its lane): a fenced
    # fragment beside the road, placed at the ground's depth, would otherwise fit a fast
    # sideways motion
    float_closing_mps: float = 2.0
    # with ``turn_across``, the rules for a floating track as oncoming traffic (docs/vru.md,
    # "An oncoming car in the fovea"): the fovea predicts its floating tracks too, and a
    # fovea track that floated stays so (the wide view fences a car oncoming at 60 km/h
    # only from a TTC of 0.7 s, the fovea from 2 s); a floating track's region cut by the
    # image's side predicts by its leading edge; its motion is fitted on the regions with
    # the ground's depth under them (elsewhere the depth is the fence's TTC at the ego's
    # speed, far too near for a car that closes faster); it may move at up to
    # ``oncoming_max_speed_mps``; once predicted, it keeps predicting while its region
    # lies across the image centre. And any region's size, like its height (``turn_across``),
    # is judged at the ground's depth under it where that lies beyond the largest fence's
    # static depth (the GVT 40 m away of a turn at 15 km/h, whose largest fence reaches
    # 12 m). Off: floating tracks predict in the wide view alone
    oncoming: bool = True
    # [m/s] a floating track's ground speed bound (``max_speed_mps`` is a road user's): a car
    # oncoming at 60 km/h, fitted on depths that err by metres from job to job
    oncoming_max_speed_mps: float = 40.0

    @property
    def oncoming_rules(self) -> bool:
        """Whether the rules for oncoming traffic apply: they refine the turn rules'
        floating tracks, so ``oncoming`` takes effect only with ``turn_across``."""
        return self.oncoming and self.turn_across

    def __post_init__(self) -> None:
        ok = (
            self.gate_frac > 0
            and self.min_gate_px >= 0
            and self.min_hits >= 2
            and self.window >= self.min_hits
            and self.max_missed >= 0
            and self.margin_m >= 0
            and self.target_half_length_m >= 0
            and self.horizon_pad_s >= 0
            and self.step_s > 0
            and self.min_ttc_s > 0
            and 0 <= self.min_speed_mps < self.max_speed_mps
            and self.min_height_m >= 0
            and self.join_rows >= 0
            and self.contact_pad_m >= 0
            and self.bearing_tol_px_per_s >= 0
            and self.hold_jobs >= 0
            and self.road_user_width_m >= 0
            and self.check_tol_px >= 0
            and self.float_closing_mps >= 0
            and self.oncoming_max_speed_mps > 0
        )
        if not ok:
            raise ValueError(f"TrackerConfig out of range: {self}")
