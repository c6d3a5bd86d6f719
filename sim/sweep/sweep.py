"""The sweep pipeline: check, plan, execute (skipping finished runs), tabulate, plot,
report. ``bittc sweep`` and ``bittc demo`` call ``run_sweep``.

Output folder::

    DIR/sweep.json      the settings (a later --resume must match them)
    DIR/runs/<config>/<case>-s<seed>/   one run: summary.json, trace.csv, config.yaml,
                        timing.json (camera.mp4 for the video cases)
    DIR/results.csv     one row per run (failed runs too, with their error)
    DIR/failures.json   run id -> traceback of the runs that failed (empty when none)
    DIR/summary.csv, DIR/summary.md, DIR/plots/*.png, DIR/report.html
    DIR/.bittc.lock     held while a sweep runs into DIR (a second one is refused)

With fixed or profile latency every file under ``DIR`` except ``timing.json``,
``report.html`` and the plots' timing notes is the same for the same settings, whatever
the backend and the worker count.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

from bittc_core.atomic import write_text_atomic
from bittc_core.errors import ConfigError
from bittc_core.parallel import LOCK_FILE, OutputLock, bounded_workers, check_workers
from sim.sweep.plan import SETTINGS_FILE, SweepSettings, check_settings, plan_runs

BACKENDS = ("local", "ray")


class SweepError(ConfigError):
    """A sweep that cannot start (bad settings, an output folder of another sweep)."""


@dataclass
class SweepOutcome:
    out: Path
    runs: int
    executed: int  # runs executed by this call (the others were finished before)
    failed: dict = field(default_factory=dict)  # run id -> traceback
    seconds: float = 0.0
    summary_md: str = ""
    report: Path | None = None

    @property
    def runs_per_min(self) -> float | None:
        return self.executed / self.seconds * 60 if self.executed and self.seconds > 0 else None


def normalized(settings: SweepSettings) -> SweepSettings:
    """Latency modes in their canonical spelling (``fixed:50.0`` -> ``fixed:50``)."""
    from sim.latency import parse_latency

    return replace(settings, latencies=tuple(dict.fromkeys(str(parse_latency(t)) for t in settings.latencies)))


def prepare_out(out: Path, settings: SweepSettings, resume: bool) -> None:
    """Refuse a folder that holds another sweep, or this one without ``resume``."""
    path = out / SETTINGS_FILE
    if path.exists():
        old = SweepSettings.from_json(path.read_text(), str(path))
        if old != settings:
            diff = [k for k in settings.__dataclass_fields__ if getattr(old, k) != getattr(settings, k)]
            raise SweepError(
                f"{out} holds a sweep of other settings ({', '.join(diff)} differ); choose another output folder"
            )
        if not resume:
            raise SweepError(f"{out} holds this sweep already; resume it, or choose another output folder")
    elif out.exists() and any(p.name != LOCK_FILE for p in out.iterdir()):
        raise SweepError(f"{out} is not empty and holds no sweep; choose another output folder")
    out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(path, settings.to_json())


def check_backend(backend: str, ray_address: str | None, workers: int) -> None:
    if backend not in BACKENDS:
        raise SweepError(f"backend {backend!r}: must be one of {', '.join(BACKENDS)}")
    if ray_address is not None and backend != "ray":
        raise SweepError("a Ray address needs the ray backend")
    try:
        check_workers(workers, local=backend != "ray")
    except ConfigError as e:
        raise SweepError(str(e)) from None
    if backend == "ray":
        try:
            import ray  # noqa: F401
        except ImportError:
            raise SweepError("the ray backend needs Ray: pip install -e '.[ray]'") from None


def _load_summary(out: Path, spec) -> dict | None:
    from sim.sweep.execute import run_dir

    path = run_dir(out, spec) / "summary.json"
    return json.loads(path.read_text()) if path.is_file() else None


def run_sweep(
    settings: SweepSettings,
    out: Path,
    *,
    workers: int = 1,
    backend: str = "local",
    ray_address: str | None = None,
    resume: bool = False,
    progress: bool = True,
    command: str = "",
) -> SweepOutcome:
    """Run every planned run not finished yet, then write the tables, plots and report.
    ``workers``: at most one per run left to do is started (``bittc_core.parallel``)."""
    settings = normalized(settings)
    cases = check_settings(settings)
    check_backend(backend, ray_address, workers)
    with OutputLock(out, "--out"):  # a second sweep into this folder is refused while this one runs
        return _run_locked(settings, cases, out, workers, backend, ray_address, resume, progress, command)


def _run_locked(settings, cases, out, workers, backend, ray_address, resume, progress, command) -> SweepOutcome:
    from sim.sweep.execute import run_local, run_ray

    prepare_out(out, settings, resume)
    plan = plan_runs(settings, cases)
    todo = [s for s in plan if _load_summary(out, s) is None]
    outcome = SweepOutcome(out, len(plan), len(todo))
    failures_path = out / "failures.json"
    old_failures = json.loads(failures_path.read_text()) if failures_path.is_file() else {}

    from tqdm import tqdm

    bar = tqdm(total=len(plan), initial=len(plan) - len(todo), unit="run", disable=not progress, smoothing=0.05)

    def on_result(res) -> None:
        if res.error is not None:
            outcome.failed[res.spec.run_id] = res.error
        bar.set_postfix_str(f"{res.spec.config_id} {res.spec.case}", refresh=False)
        bar.update(1)

    t0 = time.perf_counter()
    workers = bounded_workers(workers, len(todo), local=backend != "ray") if todo else workers
    try:
        if todo:
            if backend == "ray":
                run_ray(todo, settings, out, workers, ray_address, on_result)
            else:
                run_local(todo, settings, out, workers, on_result)
    finally:
        bar.close()
        outcome.seconds = time.perf_counter() - t0
        failures = {k: v for k, v in old_failures.items() if k not in {s.run_id for s in todo}} | outcome.failed
        write_text_atomic(failures_path, json.dumps(dict(sorted(failures.items())), indent=2) + "\n")
    outcome.failed = failures
    _write_products(out, settings, cases, plan, outcome, command, workers, backend)
    return outcome


def _write_products(out, settings, cases, plan, outcome, command, workers, backend) -> None:
    from sim.camera import CameraConfig
    from sim.sweep.plots import plot_all
    from sim.sweep.report import write_report
    from sim.sweep.tables import result_row, summarize, write_results, write_summary

    by_name = {c.name: c for c in cases}
    rows = [result_row(s, by_name[s.case], _load_summary(out, s), outcome.failed.get(s.run_id)) for s in plan]
    write_results(out / "results.csv", rows)
    summary = summarize(rows)
    outcome.summary_md = write_summary(out, summary, rows)
    plots = plot_all(out, rows, summary, 1.0 / CameraConfig().fps_hz, settings.timeline_case)
    notes = [
        f"{outcome.runs} runs; {outcome.executed} executed by the last call in {outcome.seconds:.0f} s "
        f"on {workers} {backend} worker(s)"
        + (f" ({outcome.runs_per_min:.1f} runs/min)." if outcome.runs_per_min else ".")
    ]
    if "measured" in settings.latencies:
        from bittc_core.parallel import threads_per_worker

        notes.append(
            f"Measured latency is the wall-clock time of each estimator call on this machine, with "
            f"{threads_per_worker(workers)} torch thread(s) per worker: with several workers sharing the "
            "CPU's cores each call gets fewer of them and waits for the others, so the measured latency "
            "(and with it the skipped frames) grows with the worker count. Compare measured figures only "
            "between sweeps run with the same workers on an otherwise idle machine; fixed and profile "
            "latencies do not depend on it."
        )
    if outcome.failed:
        notes.append(f"{len(outcome.failed)} run(s) failed; their errors are in failures.json.")
    videos = [r["folder"] + "/camera.mp4" for r in rows if r["folder"] and (out / r["folder"] / "camera.mp4").is_file()]
    outcome.report = write_report(out, settings.to_json(), command, summary, rows, plots, notes, videos)
