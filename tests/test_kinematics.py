"""Vehicle motion against closed-form physics."""

import math

import pytest

from sim.camera import CameraConfig
from sim.episode import ScenarioSim
from sim.traffic import TrafficVehicle
from sim.vehicles import EGO_SIZE_M
from tests.helpers import case


def run_for(c, seconds: float, decel: float = 0.0) -> ScenarioSim:
    sim = ScenarioSim(c, CameraConfig(), seed=0, render=False)
    sim.reset()
    while sim.t_s < seconds - 1e-9:
        sim.substep(decel)
    return sim


def test_constant_speed_actor_travels_v_times_t():
    sim = run_for(case(0, [{"vehicle": "car", "speed_kph": 72, "headway_m": 50}], threat=False), 2.0)
    x0 = 4.6 / 2 + 50 + sim.actors[0].spec.length_m / 2
    assert sim.actors[0].vehicle.world_pose()[0] == pytest.approx(x0 + 40.0, abs=1e-6)


def test_braking_actor_stops_after_v2_over_2a_and_never_reverses():
    v0, a = 20.0, 5.0
    sim = run_for(
        case(0, [{"vehicle": "car", "speed_kph": v0 * 3.6, "headway_m": 50, "decel_mps2": a}], threat=False), 8.0
    )
    veh = sim.actors[0].vehicle
    x0 = 4.6 / 2 + 50 + sim.actors[0].spec.length_m / 2
    assert veh.speed == 0.0
    # explicit Euler at 100 Hz overshoots the continuous v^2/2a by at most v0 * dt / 2
    assert veh.world_pose()[0] - x0 == pytest.approx(v0**2 / (2 * a), abs=v0 * 0.01)


def test_ego_actuator_delay_and_jerk_limit():
    sim = ScenarioSim(case(72, []), CameraConfig(), seed=0, render=False)
    sim.reset()
    accels = []
    for _ in range(100):
        sim.substep(9.0)
        accels.append(sim.ego.current_accel_mps2)
    act = sim.actuator
    n_delay = round(act.delay_s / sim.sim_dt_s)
    assert all(a == 0.0 for a in accels[:n_delay])
    ramp = act.max_decel_mps2 / act.jerk_mps3
    k_full = n_delay + round(ramp / sim.sim_dt_s)
    assert accels[k_full + 1] == pytest.approx(-act.max_decel_mps2)
    assert accels[n_delay] == pytest.approx(-act.jerk_mps3 * sim.sim_dt_s)


@pytest.mark.parametrize("vehicle", ["gvt", "truck"])
@pytest.mark.parametrize("overlap_pct", [100, 75, 50, 25, -25, -50, -75, -100])
def test_overlap_is_the_share_of_the_ego_width_whatever_the_target_width(vehicle, overlap_pct):
    # Euro NCAP: overlap is the share of the VUT's (ego's) width that overlaps the target
    sim = ScenarioSim(
        case(50, [{"vehicle": vehicle, "headway_s": 5, "overlap_pct": overlap_pct}]),
        CameraConfig(),
        seed=0,
        render=False,
    )
    actor = sim.actors[0]
    y_t, y_e = actor.vehicle.world_pose()[1], sim.ego.world_pose()[1]
    w_t, w_e = actor.spec.width_m, EGO_SIZE_M[1]
    shared_m = min(y_e + w_e / 2, y_t + w_t / 2) - max(y_e - w_e / 2, y_t - w_t / 2)
    if abs(overlap_pct) == 100:
        assert y_t == pytest.approx(y_e, abs=1e-9)  # centrelines aligned
        assert shared_m == pytest.approx(min(w_t, w_e), abs=1e-9)
        return
    assert shared_m / w_e == pytest.approx(abs(overlap_pct) / 100, abs=1e-9)
    assert (y_t > y_e) == (overlap_pct > 0)  # > 0: target on the ego's left
    if abs(overlap_pct) == 50:  # the target's near edge on the ego's centreline
        assert y_t - math.copysign(w_t / 2, overlap_pct) == pytest.approx(y_e, abs=1e-9)


def test_traffic_vehicles_report_the_acceleration_they_apply():
    sim = ScenarioSim(case(72, [], traffic=6), CameraConfig(), seed=0, render=False)
    truth = sim.reset()
    traffic = [a.vehicle for a in sim.actors if isinstance(a.vehicle, TrafficVehicle)]
    assert traffic
    assert all(v.current_accel_mps2 == 0.0 for v in traffic)  # before its first step
    assert sim.done(truth) is None
    seen = set()
    for _ in range(100):
        before = [float(v.speed) for v in traffic]
        sim.substep(0.0)
        for v, v0 in zip(traffic, before):
            assert v.current_accel_mps2 == pytest.approx((float(v.speed) - v0) / sim.sim_dt_s, abs=1e-6)
            seen.add(round(v.current_accel_mps2, 3))
    assert len(seen) > 1  # IDM vehicles do change speed
