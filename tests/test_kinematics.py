"""Vehicle motion against closed-form physics."""

import pytest

from sim.camera import CameraConfig
from sim.episode import ScenarioSim
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
    sim = run_for(case(0, [{"vehicle": "car", "speed_kph": v0 * 3.6, "headway_m": 50, "decel_mps2": a}], threat=False), 8.0)
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
