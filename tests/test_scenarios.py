"""Closed-loop outcomes of the bundled scenarios, determinism, and scenario validation."""

import pytest
import yaml

import controllers
import scenarios
from bittc_core.errors import ConfigError
from sim.camera import CameraConfig
from sim.runner import run_case

CAM = CameraConfig()


def outcome(name: str, controller: str) -> dict:
    return run_case(scenarios.resolve(name)[0], controllers.make(controller), CAM, seed=0)


def test_ccrs50_without_controller_collides_at_50():
    s = outcome("CCRs-50", "none")
    assert s["collision"] and s["impact_speed_kph"] == pytest.approx(50.0, abs=0.5)
    assert s["relative_impact_speed_kph"] == pytest.approx(50.0, abs=0.5)


def test_oracle_avoids_ccrs_ccrm_and_most_ccrb():
    cat = scenarios.bundled()
    for fam in ("CCRs", "CCRs-offset", "CCRm"):
        for c in cat.families[fam]:
            s = run_case(c, controllers.make("oracle"), CAM, seed=0)
            assert not s["collision"], c.name
            assert s["ttc_at_first_warning_s"] >= s["ttc_at_first_brake_s"] > 0, c.name
    ccrb = [run_case(c, controllers.make("oracle"), CAM, seed=0) for c in cat.families["CCRb"]]
    assert sum(not s["collision"] for s in ccrb) >= 3


def test_no_benign_scenario_raises_an_alarm():
    for c in scenarios.bundled().cases.values():
        if not c.threat:
            s = run_case(c, controllers.make("oracle"), CAM, seed=0)
            assert not s["false_alarm"] and s["t_first_warning_s"] is None and not s["collision"], c.name


def test_same_seed_gives_identical_outputs(tmp_path):
    c = scenarios.resolve("cut-in")[0]
    outs = []
    for i in range(2):
        d = tmp_path / f"r{i}"
        run_case(c, controllers.make("oracle"), CAM, seed=7, out_dir=d)
        outs.append(tuple((d / f).read_bytes() for f in ("trace.csv", "summary.json", "config.yaml")))
    assert outs[0] == outs[1]


def test_sweep_expansion_and_names():
    cat = scenarios.bundled()
    assert [c.name for c in cat.families["CCRs"]] == [f"CCRs-{v}" for v in range(10, 90, 10)]
    assert len(cat.families["CCRb"]) == 4
    assert scenarios.resolve("CCRs-50")[0].ego.speed_kph == 50


@pytest.mark.parametrize(
    "patch,needle",
    [
        ({"ego": {"speed_kph": -10}}, "ego.speed_kph = -10"),
        ({"actors": [{"vehicle": "gvt", "headway_s": 5, "overlap_pct": 120}]}, "overlap_pct = 120"),
        ({"actors": [{"vehicle": "gvt", "headway_s": 0}]}, "headway_s = 0"),
        ({"actors": [{"vehicle": "gvt", "headway_m": -3}]}, "headway_m = -3"),
        ({"actors": [{"vehicle": "gvt", "headway_s": 5, "speeed_kph": 3}]}, "speeed_kph"),
        ({"actors": [{"vehicle": "bus", "headway_s": 5}]}, "'bus'"),
        ({"colour": "red"}, "colour"),
        ({"ego": {"speed_kph": "fast"}}, "'fast'"),
    ],
)
def test_bad_scenario_files_are_rejected_naming_file_key_value(tmp_path, patch, needle):
    raw = {"name": "x", "threat": True, "ego": {"speed_kph": 50}, "actors": [{"vehicle": "gvt", "headway_s": 5}]}
    raw.update(patch)
    f = tmp_path / "bad.yaml"
    f.write_text(yaml.safe_dump(raw))
    with pytest.raises(ConfigError) as e:
        scenarios.resolve(str(f))
    assert str(f) in str(e.value) and needle in str(e.value)


def test_unknown_scenario_suggests_close_names():
    with pytest.raises(ConfigError, match="did you mean.*CCRs-50"):
        scenarios.resolve("CCRs-5")


def test_malformed_yaml(tmp_path):
    f = tmp_path / "m.yaml"
    f.write_text("name: [unclosed\n")
    with pytest.raises(ConfigError, match="malformed YAML"):
        scenarios.resolve(str(f))


@pytest.mark.parametrize(
    "road,needle",
    [
        ({"barrier": "no"}, "road.barrier = 'no'"),
        ({"lanes_left": 1.5}, "road.lanes_left = 1.5"),
        ({"x_end_m": 50}, "x_end_m"),
        ({"lane_width_m": [3, 4]}, "road.lane_width_m"),
    ],
)
def test_bad_road_fields_are_rejected(tmp_path, road, needle):
    raw = {"name": "x", "threat": True, "ego": {"speed_kph": 50}, "road": road, "actors": []}
    f = tmp_path / "bad.yaml"
    f.write_text(yaml.safe_dump(raw))
    with pytest.raises(ConfigError) as e:
        scenarios.resolve(str(f))
    assert needle in str(e.value)


def _refused(tmp_path, patch):
    """A valid one-actor file with ``patch`` applied: (its path, the ConfigError it raises)."""
    raw = {
        "name": "x",
        "threat": True,
        "ego": {"speed_kph": 50},
        "actors": [{"vehicle": "gvt", "headway_s": 5}],
        **patch,
    }
    f = tmp_path / "bad.yaml"
    f.write_text(yaml.safe_dump(raw))
    with pytest.raises(ConfigError) as e:
        scenarios.resolve(str(f))
    return f, e


@pytest.mark.parametrize(
    "patch,needle",
    [
        ({"name": 123}, "name = 123"),
        ({"case_name": 5}, "case_name = 5"),
        ({"name": None}, "name = None"),
        ({"case_name": ""}, "case_name = ''"),
        ({"case_name": "{"}, "case_name = '{'"),
        ({"description": 7}, "description = 7"),
    ],
)
def test_non_string_names_are_rejected_naming_the_key(tmp_path, patch, needle):
    f, e = _refused(tmp_path, patch)
    assert str(f) in str(e.value) and needle in str(e.value)


@pytest.mark.parametrize(
    "patch,key",
    [
        ({"duration_s": [10, 12]}, "duration_s"),
        ({"traffic": [0, 2]}, "traffic"),
        ({"threat": [True, False]}, "threat"),
        ({"name": ["a", "b"]}, "name"),
        ({"case_name": ["a", "b"]}, "case_name"),
        ({"description": ["a"]}, "description"),
        ({"road": {"lane_width_m": [3.0, 4.0]}}, "road.lane_width_m"),
        (
            {"actors": [{"vehicle": "gvt", "headway_s": 5, "lane_change": {"start_s": [1, 2], "to_lane": 1}}]},
            "actors[0].lane_change.start_s",
        ),
    ],
)
def test_a_list_outside_ego_and_actor_fields_is_refused(tmp_path, patch, key):
    f, e = _refused(tmp_path, patch)
    assert f"{key} = [" in str(e.value) and "only in the fields of ego and of each actor" in str(e.value)


def test_lists_in_ego_and_actor_fields_expand_into_a_sweep():
    from scenarios.spec import expand

    raw = {
        "name": "x",
        "threat": True,
        "ego": {"speed_kph": [30, 50]},
        "actors": [{"vehicle": ["gvt", "truck"], "headway_s": 5, "overlap_pct": [50, -50]}],
    }
    cases = expand(raw, "<test>")
    assert len(cases) == 8
    assert {(c.ego.speed_kph, c.actors[0].vehicle, c.actors[0].overlap_pct) for c in cases} == {
        (v, k, o) for v in (30.0, 50.0) for k in ("gvt", "truck") for o in (50.0, -50.0)
    }
