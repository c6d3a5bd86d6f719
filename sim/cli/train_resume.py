"""What an existing run at `bittc train --out` allows: no overwrite, and a `--resume` that
continues the same run (its stage, teacher and learning-rate multipliers)."""

from __future__ import annotations

from pathlib import Path

from bittc_core.errors import CliError


def check_paths(args, paths) -> None:
    """Refuse to start over an existing run, to resume a missing one, or to distil from this run's own output."""
    if args.resume and not paths.last.is_file():
        raise CliError(f"--resume: no resumable checkpoint at {str(paths.last)!r}")
    if not args.resume and (paths.last.exists() or paths.csv.exists()):
        raise CliError(
            f"--out {args.out!r}: a run already exists there ({paths.last.name}); pass --resume or choose another --out"
        )
    if args.teacher and Path(args.teacher).resolve() in (paths.best.resolve(), paths.last.resolve()):
        raise CliError(f"--teacher {args.teacher!r}: is this run's own checkpoint (--out {args.out!r} writes it)")


def stages_to_run(args, paths, distill_weight, lr_mults) -> tuple[list[str], str | None]:
    """-> (the stages to run, the stage a --resume continues or None)."""
    from bittc_core.checkpoint import load_checkpoint
    from bittc_core.train import STAGES

    stages = list(STAGES) if args.stage == "all" else [args.stage]
    if not args.resume:
        return stages, None
    last = load_checkpoint(paths.last, map_location="cpu", expected_config=args.config)
    state, meta_last = last.get("train_state", {}), last.get("train_meta", {})
    resume_stage = state.get("stage")
    _check_same_teacher(paths.last.name, meta_last, args.teacher, distill_weight, args.distill_scope or "all")
    _check_same_lr_mults(paths.last.name, meta_last, lr_mults)
    if resume_stage not in stages:
        raise CliError(f"--resume: {paths.last.name} is at stage {resume_stage!r}, not in {stages}")
    return stages[stages.index(resume_stage) :], resume_stage


def _check_same_lr_mults(name: str, meta: dict, lr_mults: tuple[tuple[str, float], ...]) -> None:
    """A resumed run keeps its learning-rate multipliers (its optimizer's groups)."""
    old = tuple((str(p), float(m)) for p, m in meta.get("train_config", {}).get("lr_mults", ()))
    if sorted(old) != sorted(lr_mults):  # the groups do not depend on the flags' order

        def show(mults):
            return " ".join(f"--lr-mult {p}={m:g}" for p, m in mults) or "no --lr-mult"

        raise CliError(f"--resume: {name} was trained with {show(old)}, not {show(lr_mults)}")


def _check_same_teacher(name: str, meta: dict, teacher: str | None, distill_weight: float, scope: str) -> None:
    """A resumed run keeps the teacher, distillation weight and scope it was started with."""
    old_teacher = meta.get("teacher")
    old_cfg = meta.get("train_config", {})
    old_weight = float(old_cfg.get("distill_weight", 0.0))
    old_scope = old_cfg.get("distill_scope", "all")
    same = (
        (old_teacher is None) == (teacher is None)
        and old_weight == distill_weight
        and (teacher is None or (Path(old_teacher).resolve() == Path(teacher).resolve() and old_scope == scope))
    )
    if not same:
        raise CliError(
            f"--resume: {name} was trained with --teacher {old_teacher!r} (distill weight {old_weight:g}, "
            f"scope {old_scope}), not --teacher {teacher!r} (distill weight {distill_weight:g}, scope {scope})"
        )
