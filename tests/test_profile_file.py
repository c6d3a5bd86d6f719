"""Device profile files: validation, `--latency profile:FILE`, and `bittc profile` itself."""

from __future__ import annotations

import csv

import pytest
import yaml

from sim.cli import main
from sim.latency import CostTerms, JobWork, LatencyError, named_profiles, parse_latency
from sim.profile_file import fit_cost_terms, read_profile_file

GOOD = {
    "name": "test-device",
    "bittc": {"extract_ms": 10.0, "view_ms": 20.0, "threshold_ms": 20.0, "job_ms": 0.0},
    "flow": {"extract_ms": 0.0, "view_ms": 5.0, "threshold_ms": 0.5, "job_ms": 1.0},
    "continuous_ms": 400.0,
    "measured": True,
    "source": "written by the test",
    "timings_ms": [{"estimator": "bittc", "views": 1, "thresholds": 1, "extractions": 1, "median_ms": 50.0}],
    "backend": "torch",
    "size_px": [96, 288],
    "threads": 2,
    "date": "2026-12-02",
}


def _write(tmp_path, doc, name="p.yaml"):
    path = tmp_path / name
    path.write_text(yaml.safe_dump(doc))
    return path


def test_a_good_file_reads_back(tmp_path):
    p = read_profile_file(_write(tmp_path, GOOD))
    assert (p.continuous_ms, p.measured) == (400.0, True)
    assert p.costs["bittc"] == CostTerms(10.0, 20.0, 20.0, 0.0)
    # a steady stream at K = 4: one extraction, one view, four thresholds
    assert p.latency_ms(JobWork("bittc", 1, 4, 1)) == 10.0 + 20.0 + 4 * 20.0
    # the fovea doubles views, thresholds and extractions; the flow baseline has its own terms
    assert p.latency_ms(JobWork("bittc", 2, 8, 2)) == 2 * 10.0 + 2 * 20.0 + 8 * 20.0
    assert p.latency_ms(JobWork("flow", 1, 16, 0)) == 1.0 + 5.0 + 16 * 0.5
    assert p.latency_ms(JobWork(None)) == 0.0


def _bad(**terms):
    return {"bittc": GOOD["bittc"] | terms}


@pytest.mark.parametrize(
    "change,needle",
    [
        ({"colour": "red"}, "unknown key.*colour"),
        (_bad(extract_ms=-1.0), "bittc.extract_ms = -1.0"),
        (_bad(view_ms=float("nan")), "view_ms = nan"),
        (_bad(threshold_ms=float("inf")), "threshold_ms = inf"),
        (_bad(job_ms="fast"), "job_ms = 'fast'"),
        ({"bittc": {"extract_ms": 1.0}}, "needs exactly the cost terms"),
        ({"a_ms": 30.0, "b_ms": 20.0}, "older profile"),
        ({"timings_ms": []}, "list of timed jobs"),
        ({"timings_ms": [{"estimator": "bittc", "median_ms": 3.0}]}, r"timings_ms\[0\] needs exactly"),
        (
            {"timings_ms": [{"estimator": "bittc", "views": 1, "thresholds": 1, "extractions": 1, "median_ms": -4.0}]},
            r"median_ms = -4.0",
        ),
        ({"measured": "yes"}, "measured = 'yes'"),
    ],
)
def test_bad_files_name_the_key(tmp_path, change, needle):
    with pytest.raises(LatencyError, match=needle):
        read_profile_file(_write(tmp_path, GOOD | change))


def test_a_file_without_cost_terms_is_refused(tmp_path):
    doc = {k: v for k, v in GOOD.items() if k not in ("bittc", "flow")}
    with pytest.raises(LatencyError, match="at least one of"):
        read_profile_file(_write(tmp_path, doc))


def test_a_family_the_profile_does_not_price_is_refused_by_name(tmp_path):
    p = read_profile_file(_write(tmp_path, {k: v for k, v in GOOD.items() if k != "flow"}))
    with pytest.raises(LatencyError, match="not the 'flow' estimator"):
        p.latency_ms(JobWork("flow", 1, 4, 0))


def test_missing_key_and_missing_file(tmp_path):
    doc = dict(GOOD)
    del doc["timings_ms"]
    with pytest.raises(LatencyError, match="missing key.*timings_ms"):
        read_profile_file(_write(tmp_path, doc))
    with pytest.raises(LatencyError, match="no such file"):
        parse_latency(f"profile:{tmp_path / 'none.yaml'}")


def test_fit_recovers_the_terms_of_exact_timings():
    truth = CostTerms(extract_ms=3.0, view_ms=5.0, threshold_ms=2.0, job_ms=1.0)
    works = [JobWork("bittc", v, v * k, v * e) for v in (1, 2) for k in (1, 4, 16) for e in (1, 2)]
    terms, rms, worst = fit_cost_terms([(w, truth.latency_ms(w)) for w in works])
    assert terms == truth and rms < 1e-9 and worst < 1e-9


def test_fit_sets_a_term_that_never_varies_to_zero():
    works = [JobWork("flow", v, v * k, 0) for v in (1, 2) for k in (1, 4, 16)]
    terms, _, _ = fit_cost_terms([(w, 4.0 * w.views + 0.1 * w.thresholds) for w in works])
    assert terms.extract_ms == 0.0 and terms.view_ms == pytest.approx(4.0) and terms.threshold_ms == pytest.approx(0.1)


def test_the_shipped_measured_profile_is_a_profile_file():
    p = named_profiles()["this-cpu"]
    assert p.measured and set(p.costs) == {"bittc", "flow"}
    assert p.costs["bittc"].threshold_ms > 0 and p.costs["flow"].view_ms > 0
    assert "bittc profile" in p.source


def test_the_arm_profile_charges_flow_its_own_terms():
    p = named_profiles()["arm-a72-assumed"]
    flow_1, flow_16 = p.stream_ms("flow", 1), p.stream_ms("flow", 16)
    assert flow_16 <= 1.5 * flow_1  # flow's cost barely grows with K, unlike the network's
    assert p.stream_ms("bittc", 16) > 3 * p.stream_ms("bittc", 1)


def test_run_charges_what_the_file_predicts(tmp_path):
    path = _write(tmp_path, GOOD)
    out = tmp_path / "run"
    argv = [
        "run",
        "CCRs-20",
        "--controller",
        "geofence",
        "--num-alphas",
        "4",
        "--latency",
        f"profile:{path}",
        "--fovea",
        "off",
        "--out",
        str(out),
    ]
    assert main(argv) == 0
    rows = list(csv.DictReader((out / "trace.csv").open()))
    lat = {float(r["latency_ms"]) for r in rows if r["latency_ms"] not in ("", "nan")}
    # steady stream: one extraction; the first job extracts both frames of its pair
    assert lat == {10.0 + 20.0 + 20.0 * 4, 2 * 10.0 + 20.0 + 20.0 * 4}


@pytest.mark.slow  # times every kind of job: about 40 s; CI runs it with -m slow
def test_bittc_profile_writes_a_file_that_run_reads(tmp_path, capsys):
    out = tmp_path / "mine.yaml"
    assert main(["profile", "--out", str(out), "--calls", "2", "--name", "ci"]) == 0
    p = read_profile_file(out)
    doc = yaml.safe_load(out.read_text())
    assert doc["name"] == "ci" and {r["estimator"] for r in doc["timings_ms"]} == {"bittc", "flow"}
    rows = doc["timings_ms"]
    # the fovea, half the wide view's width, extracts half a wide view's pixels (sim.cost_model.JobWork)
    assert {r["views"] for r in rows} == {1, 2} and {r["extractions"] for r in rows} >= {1, 1.5, 2, 3}
    assert doc["versions"]["torch"] and doc["machine"]["cpus"] >= 1
    # two calls per job on a machine running other tests: the fit is noisy (any term may come out 0,
    # all of a job's cost in its fixed term), but no term is negative, a job at K = 4 costs
    # something, and so does the continuous mode
    bittc = p.costs["bittc"]
    assert min(bittc.extract_ms, bittc.view_ms, bittc.threshold_ms, bittc.job_ms) >= 0 and p.continuous_ms > 0
    assert bittc.job_ms + bittc.view_ms + 4 * bittc.threshold_ms > 0


def test_bittc_profile_refuses_bad_output(tmp_path, capsys):
    assert main(["profile", "--out", str(tmp_path / "p.txt")]) == 2
    assert "expected a .yaml file" in capsys.readouterr().err
    assert main(["profile", "--out", str(tmp_path / "no" / "p.yaml")]) == 2
    assert not list(tmp_path.iterdir())
