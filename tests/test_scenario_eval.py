"""`bittc eval --scenarios`: the fence lag and inside share on scenario cases, open loop."""

import json

import numpy as np

import scenarios
from sim import scenario_eval
from sim.camera import CameraConfig
from sim.cli import main


class Silent:
    """An estimator whose fences are always empty."""

    dt_s = 0.1
    tau_range_s = (0.2, 10.0)

    def geofence(self, prev, latest, thresholds_s):
        return np.zeros((len(thresholds_s),) + prev.shape[:2], np.float32)


def test_a_silent_estimator_never_covers_the_target():
    case = scenarios.resolve("CCRs-30")[0]
    r = scenario_eval.evaluate_case(case, Silent(), (1.0, 2.0), CameraConfig())
    assert r.fence_lag_s == {"1": None, "2": None} and r.history and all(sh["1"] == 0 for _, sh in r.history)
    s = scenario_eval.summarize([r], (1.0, 2.0))
    assert s["fence_never_covered"] == {"1": 1, "2": 1} and s["fence_lag_s"] == {"1": None, "2": None}


def test_cli_scenario_eval_writes_json_table_and_plot(tmp_path, capsys):
    out, plot = tmp_path / "e.json", tmp_path / "share.png"
    assert (
        main(
            [
                "eval",
                "--scenarios",
                "CCRs-40",
                "--method",
                "flow",
                "--tau",
                "1.6",
                "2.4",
                "--frame-stride",
                "1",
                "--out",
                str(out),
                "--plot",
                str(plot),
            ]
        )
        == 0
    )
    r = json.loads(out.read_text())
    assert r["thresholds_s"] == [1.6, 2.4] and set(r["fence_lag_s"]) == {"1.6", "2.4"} and r["frame_stride"] == 1
    assert "CCRs-40" in r["per_case"] and r["inside_share_by_tau"]["2.4"]
    frames = r["per_case"]["CCRs-40"]["cover_share_by_frame"]  # the persistent lag again, from the frames
    taus = [tau for tau, _ in frames]
    assert len(frames) > 20 and taus[0] > 2.4 and taus[-1] < 1.0
    lags = r["per_case"]["CCRs-40"]["fence_lag_persistent_s"]
    assert any(lags[k] is not None for k in ("1.6", "2.4")), lags
    for k in ("1.6", "2.4"):
        start = None
        for tau, shares in frames[: max(j for j, t in enumerate(taus) if t <= float(k)) + 1]:
            start = (tau if start is None else start) if shares[k] >= 0.5 else None
        lag = lags[k]
        assert (lag is None and start is None) or abs(lag - (float(k) - start)) < 1e-3, (k, lag, start)
    assert plot.stat().st_size > 5000 and "median" in capsys.readouterr().out


def test_cli_scenario_eval_refuses_bad_input(tmp_path, capsys):
    out = tmp_path / "e.json"
    assert main(["eval", "--scenarios", "CCRs-40", "--method", "oracle", "--out", str(out)]) == 2
    assert main(["eval", "--scenarios", "CCRs-40", "--method", "flow", "--tau", "-1", "--out", str(out)]) == 2
    assert main(["eval", "--method", "flow", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--method 'oracle'" in err and "threshold -1.0 s" in err and "--scenarios SUITE" in err
    assert not out.exists()


def test_suites():
    ncap = scenarios.resolve_suite("ncap")
    assert {c.family for c in ncap} == {"CCRs", "CCRs-offset", "CCRm", "CCRb"} and len(ncap) == 34
    assert all(not c.threat for c in scenarios.resolve_suite("benign"))
    assert len(scenarios.resolve_suite("all")) == len(scenarios.bundled().cases)
