"""Compute latency as a real-time system sees it: latency modes, device profiles, the
streaming schedule and the command queue. Pure Python, no renderer, no network.

Convention (streaming perception, Li, Wang and Ramanan, ECCV 2020):
    The camera captures frame k at t_k = k * dt. The estimator (with the policy behind
    it) processes one frame pair at a time. A job on frame k starts at t_start >= t_k
    and its output, a brake command, takes effect at t_start + L, where L is the
    job's latency [s]. Frames are not queued: when the estimator becomes free at
    t_free it takes the newest frame captured by then (paired with the frame captured
    ``frame_stride`` frames before it, so the pair's interval stays fixed), or, if none
    is newer than its last job, the next frame at its capture time. Frames in between
    are skipped. The controller acts on the newest output that is ready. The brake
    actuator's own delay comes after the command takes effect (``sim.traffic``).

Latency modes (``parse_latency``):
    ``measured``      L = the wall-clock time of the job's own call on this machine,
                      frame by frame (not reproducible: it says so in the outputs);
    ``fixed:MS``      L = MS milliseconds (deterministic);
    ``profile:NAME``  L from a named device profile's cost model of the job's work
                      (``JobWork``: feature extractions, views, thresholds per view, for the
                      estimator that ran; ``named_profiles()``, listed by ``bittc profiles``;
                      deterministic);
    ``profile:FILE``  the same from a profile file made by ``bittc profile --out FILE``
                      (a path: it ends in .yaml / .yml or holds a /; ``sim.profile_file``).

Named profiles: the hand-written ones of ``latency_profiles.yaml`` (assumed or scaled
devices) and the measured files of ``device_profiles/`` (each made by ``bittc profile``,
named by its file name).

The cost model of a profile (``CostTerms``, one set per estimator family: the network
``bittc`` and the ``flow`` baseline), in milliseconds::

    L = job_ms + views * view_ms + thresholds * threshold_ms + extractions * extract_ms

``thresholds`` counts the thresholds evaluated over all views (K per view when every
fence runs in every view).
``extractions`` counts every frame of every view that went through the feature
extractor in the job: one per view in a steady stream, two per view after a skip (the
older frame of the pair was never extracted), none for an estimator without a feature
cache. Both count in wide-view equivalents: a view of fewer pixels (the fovea, half the
wide view's width by default) counts its pixel share of one; ``views`` counts each view
whole (its fixed cost). ``view_ms`` is the per-view work that does not grow with K (the network's
reference context, the flow field); ``threshold_ms`` the work of one threshold in one
view, the controller's region pass included; ``job_ms`` the controller's fixed work.
A controller without an estimator (the oracle) costs nothing under a profile.
"""

from __future__ import annotations

import functools
import heapq
import math
from dataclasses import dataclass
from pathlib import Path

import yaml

from sim.cost_model import (  # noqa: F401  (re-exported: the latency API)
    COST_FAMILIES,
    COST_TERMS,
    CostTerms,
    DeviceProfile,
    JobWork,
    LatencyError,
    parse_costs,
    pixel_shares,
)
from sim.profile_file import read_profile_file

PROFILES_FILE = Path(__file__).resolve().parent / "latency_profiles.yaml"
MEASURED_PROFILES_DIR = Path(__file__).resolve().parent / "device_profiles"
TIME_EPS_S = 1e-9  # [s] tolerance when comparing times on the frame grid
MAX_LATENCY_MS = 10_000.0  # [ms] a latency above this is surely a typo
_PROFILE_KEYS = {"source", "measured", "continuous_ms", *COST_FAMILIES}


def load_profiles(path: Path = PROFILES_FILE) -> dict[str, DeviceProfile]:
    """name -> profile from a YAML mapping ``{name: {bittc: {terms}, flow: {terms}, source,
    measured[, continuous_ms]}}``."""
    raw = yaml.safe_load(path.read_text())
    if not isinstance(raw, dict):
        raise LatencyError(f"{path}: expected a mapping of profile names")
    out = {}
    for name, d in raw.items():
        if not isinstance(d, dict) or set(d) - _PROFILE_KEYS or not {"source", "measured"} <= set(d):
            raise LatencyError(
                f"{path}: profile {name!r} takes the keys {sorted(_PROFILE_KEYS)} (source and measured required), "
                f"got {d!r}"
            )
        cont = d.get("continuous_ms")
        if cont is not None and not (isinstance(cont, (int, float)) and math.isfinite(cont) and cont >= 0):
            raise LatencyError(f"{path}: profile {name!r}: continuous_ms = {cont!r} must be a finite number >= 0")
        costs = parse_costs(f"{path}: profile {name!r}", {k: v for k, v in d.items() if k in COST_FAMILIES})
        out[str(name)] = DeviceProfile(str(name), costs, str(d["source"]), bool(d["measured"]), cont)
    return out


@functools.cache
def named_profiles() -> dict[str, DeviceProfile]:
    """The hand-written profiles and the measured files of ``MEASURED_PROFILES_DIR`` (read
    once, on first use)."""
    out = load_profiles()
    for path in sorted(MEASURED_PROFILES_DIR.glob("*.yaml")):
        if path.stem in out:
            raise LatencyError(f"{path}: profile {path.stem!r} is also defined in {PROFILES_FILE}")
        out[path.stem] = read_profile_file(path, name=path.stem)
    return out


def is_profile_file(arg: str) -> bool:
    return arg.endswith((".yaml", ".yml")) or "/" in arg


@dataclass(frozen=True)
class LatencyMode:
    """How a job's latency L is charged; see the module docstring."""

    kind: str  # "measured" | "fixed" | "profile"
    fixed_ms: float = 0.0  # [ms] with kind "fixed"
    profile: DeviceProfile | None = None  # with kind "profile"

    @property
    def deterministic(self) -> bool:
        return self.kind != "measured"

    def __str__(self) -> str:
        if self.kind == "fixed":
            return f"fixed:{self.fixed_ms:g}"
        if self.kind == "profile":
            return f"profile:{self.profile.name}"
        return "measured"

    def latency_s(self, compute_s: float, work: JobWork) -> float:
        """L [s] of one job that took ``compute_s`` of wall-clock time and did ``work``."""
        if self.kind == "measured":
            L = compute_s
        elif self.kind == "fixed":
            L = self.fixed_ms * 1e-3
        else:
            L = self.profile.latency_ms(work) * 1e-3
        return check_latency_s(L)


def check_latency_s(latency_s: float) -> float:
    if not (isinstance(latency_s, (int, float)) and math.isfinite(latency_s) and latency_s >= 0):
        raise LatencyError(f"latency {latency_s!r} s: must be a finite number >= 0")
    return float(latency_s)


def parse_latency(text: str, profiles: dict[str, DeviceProfile] | None = None) -> LatencyMode:
    """'measured' | 'fixed:MS' | 'profile:NAME' -> LatencyMode; anything else is refused by name."""
    profiles = named_profiles() if profiles is None else profiles
    text = str(text).strip()
    if text == "measured":
        return LatencyMode("measured")
    kind, sep, arg = text.partition(":")
    if kind == "fixed" and sep:
        try:
            ms = float(arg)
        except ValueError:
            ms = math.nan
        if not (math.isfinite(ms) and 0 <= ms <= MAX_LATENCY_MS):
            raise LatencyError(f"latency {text!r}: fixed:MS needs a number of milliseconds in [0, {MAX_LATENCY_MS:g}]")
        return LatencyMode("fixed", fixed_ms=ms)
    if kind == "profile" and sep:
        if is_profile_file(arg):
            return LatencyMode("profile", profile=read_profile_file(arg))
        if arg not in profiles:
            raise LatencyError(f"latency {text!r}: unknown profile {arg!r}; known: {', '.join(sorted(profiles))}")
        return LatencyMode("profile", profile=profiles[arg])
    raise LatencyError(f"latency {text!r}: expected measured, fixed:MS, profile:NAME or profile:FILE")


# ---------------------------------------------------------------------------- schedule
def frame_index_at(t_s: float, frame_dt_s: float) -> int:
    """Index of the newest frame captured at or before ``t_s``."""
    return int(math.floor(t_s / frame_dt_s + 1e-6))


def next_job(last_frame: int, t_free_s: float, frame_dt_s: float, first_frame: int = 0) -> tuple[int, float]:
    """The estimator became free at ``t_free_s`` after its job on ``last_frame`` (-1 before
    any job) -> (frame of its next job, the job's start time [s]).

    The newest frame captured by ``t_free_s`` if it is newer than ``last_frame``, started
    at once; otherwise the next frame, started at its capture time. Never a frame before
    ``first_frame`` (the first frame that has a partner to pair with)."""
    newest = frame_index_at(t_free_s, frame_dt_s)
    if newest > last_frame and newest >= first_frame:
        return newest, t_free_s
    k = max(last_frame + 1, first_frame)
    return k, max(k * frame_dt_s, t_free_s)


@dataclass(frozen=True)
class Job:
    """One estimator job: the frame it processes and when it starts."""

    frame: int
    capture_s: float  # [s] the frame's capture time
    start_s: float  # [s] when processing starts (>= capture_s)

    @property
    def wait_s(self) -> float:
        """[s] the frame waited for the busy estimator."""
        return self.start_s - self.capture_s


class FeatureCacheModel:
    """The estimator's per-view frame cache as the loop counts it for a profile: the last
    ``capacity`` frames used, least recently used evicted (``bittc_core.estimator.streaming``)."""

    def __init__(self, capacity: int) -> None:
        self.capacity = int(capacity)
        self._frames: list[int] = []

    def extractions(self, frames: tuple[int, ...]) -> int:
        """Use ``frames`` in this order (the older frame of the pair first); -> how many were not cached."""
        if self.capacity <= 0:
            return 0
        n = 0
        for f in frames:
            if f in self._frames:
                self._frames.remove(f)
            else:
                n += 1
            self._frames.append(f)
            del self._frames[: -self.capacity]
        return n


class CommandQueue:
    """Brake commands ordered by the time they take effect.

    ``push(t_effect_s, seq, cmd)``: ``seq`` orders the commands by the frame they were
    decided on. A due command becomes active unless a command decided on a newer frame
    is already active (an output is never replaced by an older frame's output)."""

    def __init__(self, initial) -> None:
        self._heap: list[tuple[float, int, int, object]] = []
        self._pushed = 0
        self.active = initial
        self.active_seq = -1

    def push(self, t_effect_s: float, seq: int, cmd) -> None:
        if not (isinstance(t_effect_s, (int, float)) and math.isfinite(t_effect_s)):
            raise LatencyError(f"command effect time {t_effect_s!r} s: must be a finite number")
        heapq.heappush(self._heap, (float(t_effect_s), int(seq), self._pushed, cmd))
        self._pushed += 1

    def update(self, t_s: float) -> bool:
        """Make the commands due at ``t_s`` active; True when the active command changed."""
        changed = False
        while self._heap and self._heap[0][0] <= t_s + TIME_EPS_S:
            _, seq, _, cmd = heapq.heappop(self._heap)
            if seq >= self.active_seq:
                changed |= cmd != self.active
                self.active, self.active_seq = cmd, seq
        return changed

    def __len__(self) -> int:
        return len(self._heap)
