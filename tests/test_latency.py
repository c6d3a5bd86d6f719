"""The streaming schedule, the command queue and the latency modes against hand-made cases."""

import math

import pytest

from sim.latency import CommandQueue, Job, LatencyError, next_job, parse_latency

DT = 0.1  # [s]


def schedule(latencies_s, first_frame=1, n_frames=12):
    """Hand-driven: the jobs (frame, start [s], effect [s]) for per-job latencies."""
    jobs, last, t_free = [], -1, 0.0
    for L in latencies_s:
        k, start = next_job(last, t_free, DT, first_frame)
        if k >= n_frames:
            break
        jobs.append((k, round(start, 6), round(start + L, 6)))
        last, t_free = k, start + L
    return jobs


def test_zero_latency_processes_every_frame_at_capture():
    assert schedule([0.0] * 4) == [(1, 0.1, 0.1), (2, 0.2, 0.2), (3, 0.3, 0.3), (4, 0.4, 0.4)]


def test_short_latency_waits_for_the_next_frame():
    assert schedule([0.03] * 3) == [(1, 0.1, 0.13), (2, 0.2, 0.23), (3, 0.3, 0.33)]


def test_busy_estimator_takes_the_newest_frame_and_skips_the_rest():
    # 150 ms: frame 1 at 0.1 -> free at 0.25, newest is frame 2 (0.2): starts at once;
    # free at 0.40 -> frame 4 captured then: frame 3 skipped
    assert schedule([0.15] * 3) == [(1, 0.1, 0.25), (2, 0.25, 0.4), (4, 0.4, 0.55)]
    # 250 ms: frames 3, 4 and 6 skipped
    assert schedule([0.25] * 3) == [(1, 0.1, 0.35), (3, 0.35, 0.6), (6, 0.6, 0.85)]


def test_queue_applies_commands_in_effect_order_not_arrival_order():
    q = CommandQueue("idle")
    q.push(0.50, seq=1, cmd="slow")  # decided on frame 1, long latency
    q.push(0.25, seq=2, cmd="fast")  # decided later on frame 2, short latency
    assert not q.update(0.2) and q.active == "idle"
    assert q.update(0.25) and q.active == "fast"  # did not wait for the slow one
    q.update(0.5)
    assert q.active == "fast"  # the older frame's output never replaces a newer one


def test_queue_refuses_a_nan_effect_time_instead_of_blocking():
    q = CommandQueue("idle")
    with pytest.raises(LatencyError, match="nan"):
        q.push(math.nan, seq=1, cmd="x")
    q.push(0.1, seq=2, cmd="y")
    q.update(0.1)
    assert q.active == "y" and len(q) == 0


def test_latency_modes():
    assert parse_latency("fixed:50").latency_s(1.0, 4) == pytest.approx(0.05)
    assert parse_latency("measured").latency_s(0.0123, 4) == pytest.approx(0.0123)
    p = parse_latency("profile:this-cpu")
    assert p.latency_s(0.0, 4) == pytest.approx((p.profile.a_ms + 4 * p.profile.b_ms) * 1e-3)
    assert p.deterministic and not parse_latency("measured").deterministic
    with pytest.raises(LatencyError, match="nan"):
        parse_latency("measured").latency_s(math.nan, 1)


@pytest.mark.parametrize("bad", ["fixed", "fixed:", "fixed:abc", "fixed:-5", "fixed:nan", "profile:nope", "slow", ""])
def test_malformed_latency_modes_are_refused_by_name(bad):
    with pytest.raises(LatencyError, match="latency"):
        parse_latency(bad)


def test_job_wait():
    assert Job(2, 0.2, 0.25).wait_s == pytest.approx(0.05)
