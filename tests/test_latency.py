"""The streaming schedule, the command queue and the latency modes against hand-made cases."""

import math

import pytest

from sim.latency import CommandQueue, FeatureCacheModel, Job, JobWork, LatencyError, next_job, parse_latency

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
    work = JobWork("bittc", views=1, thresholds=4, extractions=1)
    assert parse_latency("fixed:50").latency_s(1.0, work) == pytest.approx(0.05)
    assert parse_latency("measured").latency_s(0.0123, work) == pytest.approx(0.0123)
    p = parse_latency("profile:this-cpu")
    c = p.profile.costs["bittc"]
    assert p.latency_s(0.0, work) == pytest.approx((c.job_ms + c.view_ms + 4 * c.threshold_ms + c.extract_ms) * 1e-3)
    assert p.deterministic and not parse_latency("measured").deterministic
    with pytest.raises(LatencyError, match="nan"):
        parse_latency("measured").latency_s(math.nan, work)


def test_a_profile_charges_every_extraction_view_and_threshold():
    p = parse_latency("profile:arm-a72-assumed").profile
    c = p.costs["bittc"]
    stream, after_skip = JobWork("bittc", 1, 4, 1), JobWork("bittc", 1, 4, 2)
    assert p.latency_ms(after_skip) - p.latency_ms(stream) == pytest.approx(c.extract_ms)
    fovea = JobWork("bittc", 2, 8, 2)
    assert p.latency_ms(fovea) - p.latency_ms(stream) == pytest.approx(c.view_ms + 4 * c.threshold_ms + c.extract_ms)
    assert p.latency_ms(JobWork(None)) == 0.0  # the oracle computes nothing a profile prices


def test_feature_cache_model_counts_what_the_estimator_extracts():
    cache = FeatureCacheModel(4)
    assert cache.extractions((0, 2)) == 2  # the first pair: both frames
    assert cache.extractions((1, 3)) == 2  # stride 2, every frame: frame 1 was never seen
    assert cache.extractions((2, 4)) == 1  # steady stream
    assert cache.extractions((3, 5)) == 1
    assert cache.extractions((6, 8)) == 2  # after a skip the older frame is new too
    assert FeatureCacheModel(0).extractions((0, 1)) == 0  # no cache: nothing counted (flow)


def test_the_cache_holds_the_default_stride():
    """The estimator's LRU cache keeps the older frame of a (k - n, k) stream for n up to the
    controller's default stride: one extraction a job once the stream runs."""
    from bittc_core.estimator.streaming import CACHED_FRAMES
    from controllers.geofence import DEFAULT_FRAME_STRIDE

    n = DEFAULT_FRAME_STRIDE
    cache = FeatureCacheModel(CACHED_FRAMES)
    counts = [cache.extractions((k - n, k)) for k in range(n, n + 10)]
    assert counts[:n] == [2] * n and counts[n:] == [1] * (10 - n)


@pytest.mark.parametrize("bad", ["fixed", "fixed:", "fixed:abc", "fixed:-5", "fixed:nan", "profile:nope", "slow", ""])
def test_malformed_latency_modes_are_refused_by_name(bad):
    with pytest.raises(LatencyError, match="latency"):
        parse_latency(bad)


def test_job_wait():
    assert Job(2, 0.2, 0.25).wait_s == pytest.approx(0.05)
