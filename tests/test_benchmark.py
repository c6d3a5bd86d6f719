"""The latency benchmark's arithmetic and protocol (timings themselves are never asserted)."""

from __future__ import annotations

import numpy as np
import pytest

from bittc_core.benchmark import BenchSettings, extra_threshold_ratios, interleaved_median_ms


def test_extra_threshold_ratios_of_a_linear_cost():
    # t_K = 10 ms + 2.5 ms per extra threshold -> every ratio and the slope are 0.25
    ratios, slope = extra_threshold_ratios({k: 10.0 + 2.5 * (k - 1) for k in (1, 2, 4, 8, 16, 24)})
    assert set(ratios) == {2, 4, 8, 16, 24}
    assert all(r == pytest.approx(0.25) for r in ratios.values())
    assert slope == pytest.approx(0.25)


def test_extra_threshold_ratios_see_a_superlinear_cost():
    ratios, _ = extra_threshold_ratios({1: 10.0, 2: 12.0, 24: 10.0 + 23 * 4.0})
    assert ratios[2] == pytest.approx(0.2) and ratios[24] == pytest.approx(0.4)


def test_interleaved_rounds_call_every_setting_on_the_same_pairs_in_turn():
    seen = []
    calls = {name: (lambda a, b, n=name: seen.append((n, a, b))) for name in ("x", "y")}
    ms = interleaved_median_ms(calls, [0, 1, 2, 3], warmup=1)
    assert seen == [("x", 0, 1), ("y", 0, 1), ("y", 1, 2), ("x", 1, 2), ("x", 2, 3), ("y", 2, 3)]
    assert set(ms) == {"x", "y"} and all(v >= 0 for v in ms.values())


@pytest.mark.parametrize("ks", [(2, 4), (1,), (1, 2, 2)])
def test_settings_need_one_threshold_and_another_distinct_k(ks):
    with pytest.raises(ValueError, match="K = 1"):
        BenchSettings(thresholds=ks)


def test_settings_need_a_warmup_round():
    with pytest.raises(ValueError, match="warmup=0"):
        BenchSettings(warmup=0)


@pytest.mark.parametrize(
    "size, needle", [("95x288", "multiples of 3"), ("96by288", "expected HxW"), ("9x288", "height must be in")]
)
def test_bench_refuses_a_bad_size_before_timing(size, needle, capsys):
    from sim.cli import main

    assert main(["bench", "--size", size, "--calls", "1"]) == 2
    captured = capsys.readouterr()
    assert needle in captured.err and size in captured.err
    assert "config" not in captured.out  # no timing table began


def test_bench_times_the_size_it_is_given(capsys):
    from sim.cli import main

    assert main(["bench", "--config", "tiny", "--size", "48x96", "--calls", "1", "--threads", "1"]) == 0
    assert "48x96 px" in capsys.readouterr().out


@pytest.mark.slow  # whole jobs of both views, timed: about 40 s; CI runs it with -m slow
def test_bench_fovea_writes_one_row_per_job(tmp_path, capsys):
    import json

    from sim.cli import main

    out = tmp_path / "bench.json"
    assert main(["bench", "--fovea", "off", "4", "--calls", "1", "--out", str(out)]) == 0
    rows = json.loads(out.read_text())["rows"]
    keys = {"backend", "fovea_zoom", "num_alphas", "output", "tta", "median_ms"}
    assert all(set(r) == keys for r in rows)
    binary = {(r["fovea_zoom"], r["num_alphas"]): r["median_ms"] for r in rows if r["output"] == "binary"}
    assert set(binary) == {(z, k) for z in (None, 4.0) for k in (1, 2, 4, 8, 16, 24)}
    assert {r["fovea_zoom"] for r in rows if r["output"] == "continuous"} == {None, 4.0}
    # one call per job on a machine running other tests: the times are real, not comparable
    assert all(np.isfinite(v) and v > 0 for v in binary.values())
    assert main(["bench", "--fovea", "0.5", "--out", str(tmp_path / "x.json")]) == 2
    assert main(["bench", "--out", str(tmp_path / "x.json")]) == 2
    assert not (tmp_path / "x.json").exists()
