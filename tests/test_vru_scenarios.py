"""Road-user and junction scenarios: the bundled suites, their checks, the oracle on them."""

import math

import pytest
import yaml

import scenarios
from bittc_core.errors import ConfigError
from controllers.oracle import OracleController
from scenarios.protocols import PROTOCOLS
from sim.camera import CameraConfig
from sim.cli import main
from sim.episode import ScenarioSim
from sim.ncap_score import family_rows, impact_share, points, unavoidable_reason

VRU_ROAD = {"lanes_left": 1, "lanes_right": 1, "sidewalk_m": 3.0, "barrier": False}


def test_the_suites_hold_enough_cases_and_name_their_protocols():
    counts = {s: len(scenarios.resolve_suite(s)) for s in ("vru", "junction", "benign-vru")}
    assert counts["vru"] >= 40 and counts["junction"] >= 15 and counts["benign-vru"] >= 8, counts
    for s in ("vru", "junction", "benign-vru"):
        for c in scenarios.resolve_suite(s):
            assert c.protocol in PROTOCOLS and c.protocol, c.name
    # the earlier benign suite keeps its cases: straight road, vehicles only
    assert all(not c.open_paths and not c.threat for c in scenarios.resolve_suite("benign"))
    assert {c.name for c in scenarios.resolve_suite("benign-vru")}.isdisjoint(
        c.name for c in scenarios.resolve_suite("benign")
    )


def _file(tmp_path, **over):
    raw = {
        "name": "mine",
        "protocol": "euro-ncap-aeb-vru-4.5.1",
        "threat": True,
        "duration_s": 6,
        "road": dict(VRU_ROAD),
        "ego": {"speed_kph": 40},
        "actors": [{"pedestrian": "adult", "path": "nearside", "speed_kph": 5, "impact_pct": 50}],
    }
    for k, v in over.items():
        raw[k] = v
    p = tmp_path / "mine.yaml"
    p.write_text(yaml.safe_dump(raw))
    return p


BAD = [
    ({"ego": {"speed_kph": 20, "turn": "left"}}, "ego.turn"),  # a turn with no junction leaves the road
    (
        {"actors": [{"pedestrian": "adult", "path": "longitudinal", "speed_kph": 5, "lateral_m": -15}]},
        "actors[0].path",  # walks 15 m right of the ego: off the road and its sidewalks
    ),
    ({"actors": [{"pedestrian": "adult", "path": "nearside", "speed_kph": 0, "impact_pct": 50}]}, "speed_kph"),
    (
        {"actors": [{"pedestrian": "child", "path": "nearside", "speed_kph": 5, "impact_pct": 50, "height_m": 1.9}]},
        "actors[0].height_m",
    ),
    ({"protocol": "euro-ncap-aeb-vru-9.9"}, "protocol"),
    (
        {"actors": [{"vehicle": "car", "direction": "from_left", "speed_kph": 30, "offset_s": 0}]},
        "actors[0].direction",  # a crossing car needs a junction
    ),
]


@pytest.mark.parametrize("over,field", BAD, ids=[f for _, f in BAD])
def test_bad_scenarios_are_refused_by_field_with_exit_2_and_nothing_written(tmp_path, capsys, over, field):
    path = _file(tmp_path, **over)
    with pytest.raises(ConfigError, match=field.replace("[", r"\[").replace("]", r"\]")):
        scenarios.load_file(path)
    out = tmp_path / "run"
    assert main(["run", str(path), "--controller", "oracle", "--out", str(out)]) == 2
    assert field in capsys.readouterr().err
    assert not out.exists()


def test_a_good_file_expands_and_its_pedestrian_meets_the_ego(tmp_path):
    (case,) = scenarios.load_file(_file(tmp_path))
    sim = ScenarioSim(case, CameraConfig(), seed=0, render=False)
    truth = sim.reset()
    ped = truth.actors[0]
    assert ped.in_path and ped.ahead
    # conflict_s = 4 s: the ego's front reaches the pedestrian's line at 4 s, where it stands in the ego's path
    assert ped.ttc_s == pytest.approx(4.0, abs=0.05)
    assert ped.closing_speed_mps == pytest.approx(40 / 3.6, rel=1e-6)


ORACLE_CASES = ["CPNA-25-40", "CPFA-50-60", "CPNCO-50-30", "CBNA-50-20", "CBLA-50-50", "CCFtap-15-45"]
ORACLE_CASES += ["CCCscp-from_left-40"]


@pytest.mark.parametrize("name", ORACLE_CASES)
def test_the_oracle_avoids_what_no_braking_hits(name):
    case = scenarios.resolve(name)[0]
    assert unavoidable_reason(case) is None
    for controller, hit in ((None, True), (OracleController(), False)):
        sim = ScenarioSim(case, CameraConfig(), seed=0, render=False)
        truth = sim.reset()
        if controller is not None:
            controller.reset()
        while sim.done(truth) is None:
            decel = controller.act(None, truth).decel_mps2 if controller is not None else 0.0
            for _ in range(sim.n_sub):
                sim.substep(decel)
            truth = sim.truth()
        assert (sim.collision is not None) == hit, (name, controller)


def test_head_on_is_marked_unavoidable_and_scored_by_impact_speed():
    case = scenarios.resolve("CCFhos-50-50")[0]
    assert "stopped" in unavoidable_reason(case)
    s = {"threat": True, "collision": True, "impact_speed_kph": 10.0, "test_speed_kph": 40.0}
    assert points(s) == pytest.approx(0.75)
    assert points({**s, "collision": False}) == 1.0
    rows = family_rows(
        [
            {**s, "family": "A", "false_alarm": False, "unavoidable": None},
            {"family": "A", "threat": False, "collision": False, "false_alarm": True, "impact_speed_kph": None},
        ]
    )
    assert rows == [
        {
            "family": "A",
            "cases": 2,
            "threats": 1,
            "avoided": 0,
            "avoidable": 1,
            "false_alarms": 1,
            "benign": 1,
            "mean_impact_kph": 10.0,
            "points": 0.75,
        }
    ]
    # the rest's mean impact share leaves out what braking cannot avoid
    hit = {**s, "unavoidable": None}
    assert impact_share([hit, {**hit, "impact_speed_kph": 30.0}]) == pytest.approx(0.5)
    assert impact_share([hit, {**hit, "impact_speed_kph": 40.0, "unavoidable": "stopped"}]) == pytest.approx(0.25)
    assert impact_share([{**hit, "collision": False}]) is None


def test_a_left_turn_follows_the_arc_and_reports_its_yaw_rate():
    case = scenarios.resolve("benign-tap-passed-20")[0]
    sim = ScenarioSim(case, CameraConfig(), seed=0, render=False)
    sim.reset()
    path, worst, yaw = case.path, 0.0, []
    while sim.t_s < 8.0:
        sim.substep(0.0)
        x, y, _ = sim.ego.world_pose()
        px, py, _ = path.pose_at(path.closest_s(x, y))
        worst = max(worst, math.hypot(x - px, y - py))
        yaw.append(sim.ego.yaw_rate_radps)
    assert worst < 0.8  # pure pursuit stays within 0.8 m of the nominal arc
    assert max(yaw) == pytest.approx(20 / 3.6 / path.radius_m, rel=0.25)  # v / R on the arc, turning left
    assert sim.ego.world_pose()[2] == pytest.approx(math.pi / 2, abs=0.1)
