"""Device profile files: validation, `--latency profile:FILE`, and `bittc profile` itself."""

from __future__ import annotations

import csv

import pytest
import yaml

from bittc_core.cli import main
from sim.latency import LatencyError, named_profiles, parse_latency
from sim.profile_file import fit_latency, read_profile_file

GOOD = {
    "name": "test-device",
    "a_ms": 30.0,
    "b_ms": 20.0,
    "continuous_ms": 400.0,
    "measured": True,
    "source": "written by the test",
    "timings_ms": {"binary": {1: 50.0, 2: 70.0, 4: 110.0}, "continuous": 400.0},
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
    assert (p.a_ms, p.b_ms, p.continuous_ms, p.measured) == (30.0, 20.0, 400.0, True)
    assert p.latency_ms(4) == 110.0


@pytest.mark.parametrize(
    "change,needle",
    [
        ({"colour": "red"}, "unknown key.*colour"),
        ({"a_ms": -1.0}, "a_ms = -1.0"),
        ({"b_ms": float("nan")}, "b_ms = nan"),
        ({"b_ms": float("inf")}, "b_ms = inf"),
        ({"a_ms": "fast"}, "a_ms = 'fast'"),
        ({"timings_ms": {"binary": {}}}, "at least two K"),
        ({"timings_ms": {"continuous": 3.0}}, "at least two K"),
        ({"timings_ms": {"binary": {1: 5.0, 0: 4.0}}}, "K = 0"),
        ({"timings_ms": {"binary": {1: 5.0, 2: -4.0}}}, r"binary\[2\] = -4.0"),
        ({"measured": "yes"}, "measured = 'yes'"),
    ],
)
def test_bad_files_name_the_key(tmp_path, change, needle):
    with pytest.raises(LatencyError, match=needle):
        read_profile_file(_write(tmp_path, GOOD | change))


def test_missing_key_and_missing_file(tmp_path):
    doc = dict(GOOD)
    del doc["timings_ms"]
    with pytest.raises(LatencyError, match="missing key.*timings_ms"):
        read_profile_file(_write(tmp_path, doc))
    with pytest.raises(LatencyError, match="no such file"):
        parse_latency(f"profile:{tmp_path / 'none.yaml'}")


def test_fit_is_least_squares():
    a, b, rms, worst = fit_latency({1: 10.0, 2: 12.0, 4: 16.0, 8: 24.0})
    assert abs(a - 8.0) < 1e-9 and abs(b - 2.0) < 1e-9 and rms < 1e-9 and worst < 1e-9


def test_the_shipped_measured_profile_is_a_profile_file():
    p = named_profiles()["this-cpu"]
    assert p.measured and p.a_ms > 0 and p.b_ms > 0
    assert "bittc profile" in p.source


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
        "--out",
        str(out),
    ]
    assert main(argv) == 0
    rows = list(csv.DictReader((out / "trace.csv").open()))
    lat = {float(r["latency_ms"]) for r in rows if r["latency_ms"] not in ("", "nan")}
    assert lat == {30.0 + 20.0 * 4}


def test_bittc_profile_writes_a_file_that_run_reads(tmp_path, capsys):
    out = tmp_path / "mine.yaml"
    assert main(["profile", "--out", str(out), "--calls", "2", "--name", "ci"]) == 0
    p = read_profile_file(out)
    doc = yaml.safe_load(out.read_text())
    assert doc["name"] == "ci" and set(doc["timings_ms"]["binary"]) == {1, 2, 4, 8, 16, 24}
    assert doc["versions"]["torch"] and doc["machine"]["cpus"] >= 1
    assert p.b_ms > 0 and p.continuous_ms > 0


def test_bittc_profile_refuses_bad_output(tmp_path, capsys):
    assert main(["profile", "--out", str(tmp_path / "p.txt")]) == 2
    assert "expected a .yaml file" in capsys.readouterr().err
    assert main(["profile", "--out", str(tmp_path / "no" / "p.yaml")]) == 2
    assert not list(tmp_path.iterdir())
