"""Braking holds until the contact time its last firing bounded (``GeofenceConfig.
hold_to_contact``): a target that leaves every fence test when it is near is still ahead."""

import numpy as np
import pytest

import tests.geofence_maps as gc
from controllers.base import Observation
from controllers.geofence import GeofenceConfig, GeofenceController


def _commands(hold: bool, dist_m: float = 20.0, seen_jobs: int = 3, jobs: int = 24) -> list:
    """Commands per job (0.1 s apart) at 50 km/h: a static car ``dist_m`` ahead in the
    corridor (20 m: TTC 1.44 s, the partial stage, the 1.8 s fence) for ``seen_jobs`` jobs,
    then in no fence."""
    est = gc.MapEstimator()
    cfg = GeofenceConfig(thresholds_s=gc.THR, frame_stride=1, hold_to_contact=hold)
    ctrl = GeofenceController(est, cfg)
    ctrl.reset(gc.CAL)
    img = np.zeros((gc.CAM.height_px, gc.CAM.width_px, 3), np.uint8)
    seen, gone = gc.add_box(gc.road(), dist_m, 0.0, dist_m / gc.SPEED), gc.road()
    out = []
    for k in range(jobs):
        est.tau = seen if k < seen_jobs else gone
        out.append(ctrl.act(Observation(0.1 * k, gc.SPEED, img, img, 0.1, gc.CAL), None))
    return out


@pytest.mark.parametrize("hold", [True, False])
def test_braking_holds_until_the_bounded_contact_time(hold):
    d = [c.decel_mps2 for c in _commands(hold)]
    assert d[0] == 0 and d[1] > 0 and d[2] > 0  # fired at 0.1 s and 0.2 s, in the 1.8 s fence
    # without the hold: released after release_frames (3) jobs with no fence firing
    last_braked = max(k for k, v in enumerate(d) if v > 0)
    if hold:  # until 0.2 s + 1.8 s: the contact the last firing bounded
        assert last_braked == 19
    else:
        assert last_braked == 4


def test_a_warning_alone_is_not_held():
    # 35 m ahead (TTC 2.5 s): only the 2.8 s fence fires, a warning without braking; it is
    # released after release_frames (3) jobs with no fence firing, hold or not
    cmds = _commands(True, dist_m=2.5 * gc.SPEED)
    assert cmds[1].warning and not any(c.decel_mps2 for c in cmds)
    assert max(k for k, c in enumerate(cmds) if c.warning) == 4
