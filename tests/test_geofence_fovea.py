"""The geofence controller with the fovea beside the wide view, on hand-made maps."""

from controllers.geofence import GeofenceConfig, GeofenceController
from tests.geofence_maps import (
    FOVEA_CAL,
    THR,
    ViewMapEstimator,
    add_box,
    fovea_box,
    road,
    run_two_views,
)


def test_a_target_seen_only_by_the_fovea_fires_in_the_fovea():
    # 35 m ahead at 50 km/h: a static face at tau 2.5 s, inside the 2.8 s fence, too small for the wide view
    ctrl, cmds = run_two_views(road(), fovea_box(35.0, 2.5))
    # the fovea runs the fences from DEFAULT_FOVEA_FENCES_FROM_S (1.4 s) on: 1.8 and 2.8 s
    assert ctrl.views == ("wide", "fovea") and ctrl.job_thresholds == len(THR) + 2
    last = cmds[-1].telemetry
    assert last["fired_view"] == "fovea" and last["fence_fired_s"] == 2.8 and cmds[-1].warning
    assert last["inpath_px_fovea_2.8s"] > 100 and last["inpath_px_2.8s"] == 0
    assert cmds[-1].fovea_view is not None and cmds[-1].fovea_view.counted.any()


def test_the_most_urgent_view_decides():
    # the wide view sees the face inside the 1.2 s fence, the fovea only inside 2.8 s: the wide view's stage wins
    near = add_box(road(), 16.0, 0.0, 1.1)
    _, cmds = run_two_views(near, fovea_box(35.0, 2.5))
    assert cmds[-1].telemetry["fired_view"] == "wide" and cmds[-1].telemetry["fence_fired_s"] == 1.2
    assert cmds[-1].decel_mps2 > 0


def test_fences_below_the_fovea_bound_run_on_the_wide_view_only():
    est = ViewMapEstimator()
    ctrl = GeofenceController(est, GeofenceConfig(thresholds_s=THR, frame_stride=1, fovea_fences_from_s=1.5))
    ctrl.reset(FOVEA_CAL)
    assert ctrl.job_thresholds == 4 + 2  # the 1.8 and 2.8 s fences in the fovea too
    # a bound above every fence leaves the fovea its largest
    above = GeofenceController(est, GeofenceConfig(thresholds_s=THR, fovea_fences_from_s=3.0))
    above.reset(FOVEA_CAL)
    assert above.view_thresholds == {"wide": 4, "fovea": 1}
