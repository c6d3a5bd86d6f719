"""The flags of `bittc train`: their definitions and the checks of their values."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from bittc_core.errors import CliError
from bittc_core.model.config import CONFIGS
from bittc_core.train.config import DISTILL_SCOPES
from sim.cli.common import add_device_flag, add_seed_flag, check_device, check_seed

STAGE_CHOICES = ("flow", "binary", "continuous", "all")


def add_train_flags(p: argparse.ArgumentParser) -> None:
    """Every flag of `bittc train`, in the order ``--help`` lists them."""
    p.add_argument("--data", required=True, help="dataset folder, or 'synthetic' for the built-in generator")
    p.add_argument(
        "--config",
        required=True,
        help=f"model config name ({', '.join(CONFIGS)})",
    )
    p.add_argument("--out", required=True, help="best checkpoint path, *.pt")
    p.add_argument(
        "--frame-stride",
        type=int,
        default=1,
        metavar="N",
        help="the dataset's pairs span N of the network's frame intervals, and it learns to read them "
        "at its own interval (time compressed N x, as `bittc run --frame-stride N` feeds it; default 1)",
    )
    p.add_argument("--resume", action="store_true", help="continue from <stem>.last.pt")
    p.add_argument(
        "--init",
        default=None,
        help="start from the weights of this checkpoint (same config, or a config "
        "this one grows from, such as cpu-small for cpu-medium or cpu-small-corr: the added blocks start as the "
        "identity)",
    )
    add_seed_flag(p, "seed of the initial weights, the data order and the augmentation")
    p.add_argument("--steps", type=int, default=2000, help="optimiser steps per stage (default 2000)")
    p.add_argument("--batch-size", type=int, default=8, help="image pairs per optimiser step (default 8)")
    p.add_argument("--lr", type=float, default=3e-4, help="peak learning rate (default 3e-4)")
    p.add_argument(
        "--warmup-steps",
        type=int,
        default=200,
        help="linear warm-up steps before the cosine decay, per stage (default 200)",
    )
    p.add_argument("--val-every", type=int, default=250, help="steps between validations")
    p.add_argument("--val-limit", type=int, default=64, help="validation pairs")
    p.add_argument(
        "--keep-checkpoints",
        action="store_true",
        help="also keep the weights of every validation step, <stem>.<stage>.step<NNNNNN>.pt beside --out "
        "(for weight averaging: bittc weights average)",
    )
    add_device_flag(p)
    p.add_argument(
        "--stage", default="binary", choices=STAGE_CHOICES, help="flow, binary, continuous or all (default binary)"
    )
    _add_loss_flags(p)
    _add_what_learns_flags(p)


def _add_loss_flags(p: argparse.ArgumentParser) -> None:
    """The flags that shape a stage's loss and what learns."""
    p.add_argument(
        "--actor-weight",
        type=float,
        default=1.0,
        help="binary stage: loss weight of vehicle (actor) pixels, moving or not; scenery pixels 1 (default 1)",
    )
    p.add_argument(
        "--inpath-weight",
        type=float,
        default=1.0,
        help="binary stage: loss weight of in-path vehicle pixels (within 1.5 m of the camera's axis, "
        "nearer than 80 m times a fovea sample's zoom), instead of --actor-weight there (default 1)",
    )
    p.add_argument(
        "--vru-weight",
        type=float,
        default=1.0,
        help="binary stage: loss weight of pedestrian and cyclist pixels, instead of the two above there (default 1)",
    )
    p.add_argument(
        "--near-outside-weight",
        type=float,
        default=1.0,
        help="binary stage: loss weight of scenery pixels outside a threshold's fence with a TTC at most "
        "twice the threshold (the road just past a fence's static depth), instead of 1 (default 1)",
    )
    p.add_argument(
        "--lovasz-weight",
        type=float,
        default=0.0,
        help="binary stage: add this weight x a Lovasz surrogate of the per-map two-class IoU to the BCE (default 0)",
    )
    p.add_argument(
        "--pixel-thresholds",
        type=float,
        default=0.0,
        metavar="SHARE",
        help="binary stage: this share of the eta thresholds at the eta of a random valid pixel of "
        "each pair (jittered), the rest uniform (default 0)",
    )
    p.add_argument(
        "--inpath-thresholds",
        type=float,
        default=0.0,
        metavar="SHARE",
        help="binary stage: this share of the eta thresholds at the eta of a random in-path vehicle pixel "
        "of each pair (jittered by +-0.005), beside --pixel-thresholds' share; uniform for a pair without "
        "one (default 0)",
    )
    p.add_argument(
        "--teacher",
        default=None,
        help="binary stage: also learn the flip-averaged maps of this frozen checkpoint (same config; "
        "self-distillation, soft BCE targets beside the ground truth; each step also runs the teacher "
        "on both views of its pairs)",
    )
    p.add_argument(
        "--distill-weight",
        type=float,
        default=None,
        help="with --teacher: weight of the distillation BCE beside the ground-truth BCE (default 1); "
        "with a --distill-scope other than 'all', the weight of the taught pixels against the ground truth's",
    )
    p.add_argument(
        "--distill-scope",
        choices=DISTILL_SCOPES,
        default=None,
        help="with --teacher: 'all' (default) adds the teacher's term beside the ground truth on every "
        "pixel; 'scenery' replaces the ground truth by the teacher's maps on scenery pixels only "
        "(weighted by --distill-weight), the actors (vehicles, road users) keep the ground truth; "
        "'scenery-vehicles' on vehicles too, only pedestrians and cyclists keep it",
    )


def _add_what_learns_flags(p: argparse.ArgumentParser) -> None:
    """Which parameters learn, at what rate, and whether the batch norms' statistics move."""
    p.add_argument(
        "--lr-mult",
        action="append",
        default=[],
        metavar="PREFIX=M",
        help="parameters whose names start with PREFIX learn at M x the learning rate, and decay "
        "at M x the weight decay (repeatable; e.g. segnet.corr_=10 for the correlation convs "
        "that --init added at zero; --resume needs the same flags)",
    )
    p.add_argument(
        "--freeze-binary",
        action="store_true",
        help="continuous stage: train the continuous refinement only, the binary network frozen",
    )
    p.add_argument(
        "--freeze-norm-stats",
        action="store_true",
        help="keep every batch norm's running statistics as --init had them (their scale and "
        "shift still learn), e.g. for a fine-tune on pairs of another --frame-stride",
    )


def check_train_flags(args) -> None:
    """Refuse a bad value or combination of flags, naming the flag, before anything is read or written."""
    from bittc_core.model import CONFIGS

    if args.config not in CONFIGS:
        raise CliError(f"--config {args.config!r}: expected one of {sorted(CONFIGS)}")
    if args.stage not in STAGE_CHOICES:
        raise CliError(f"--stage {args.stage!r}: expected one of {STAGE_CHOICES}")
    check_device(args.device)
    for flag, value in (
        ("--frame-stride", args.frame_stride),
        ("--steps", args.steps),
        ("--batch-size", args.batch_size),
        ("--val-every", args.val_every),
        ("--val-limit", args.val_limit),
    ):
        if value <= 0:
            raise CliError(f"{flag} {value}: must be > 0")
    check_seed(args.seed)
    if not 0 < args.lr < 1:
        raise CliError(f"--lr {args.lr}: must be in (0, 1)")
    if args.warmup_steps < 0:
        raise CliError(f"--warmup-steps {args.warmup_steps}: must be >= 0")
    if not args.out.endswith(".pt"):
        raise CliError(f"--out {args.out!r}: expected a file name ending in .pt")
    if not 0 < args.actor_weight < math.inf:
        raise CliError(f"--actor-weight {args.actor_weight}: must be > 0 and finite")
    if not 0 < args.inpath_weight < math.inf:
        raise CliError(f"--inpath-weight {args.inpath_weight}: must be > 0 and finite")
    if not 0 < args.vru_weight < math.inf:
        raise CliError(f"--vru-weight {args.vru_weight}: must be > 0 and finite")
    if not 0 < args.near_outside_weight < math.inf:
        raise CliError(f"--near-outside-weight {args.near_outside_weight}: must be > 0 and finite")
    if not 0 <= args.lovasz_weight < math.inf:
        raise CliError(f"--lovasz-weight {args.lovasz_weight}: must be >= 0 and finite")
    if not 0 <= args.pixel_thresholds <= 1:
        raise CliError(f"--pixel-thresholds {args.pixel_thresholds}: must be in [0, 1]")
    if not 0 <= args.inpath_thresholds <= 1 - args.pixel_thresholds:
        raise CliError(
            f"--inpath-thresholds {args.inpath_thresholds}: must be in [0, 1 - --pixel-thresholds "
            f"= {1 - args.pixel_thresholds:g}]"
        )
    if args.freeze_norm_stats and args.init is None and not args.resume:
        raise CliError("--freeze-norm-stats needs --init: it keeps the statistics of trained weights")
    if args.freeze_norm_stats and CONFIGS[args.config].norm != "batch":
        raise CliError(f"--freeze-norm-stats: config {args.config!r} has no batch norm")
    if args.freeze_binary and args.stage not in ("continuous", "all"):
        raise CliError(f"--freeze-binary applies to the continuous stage, not --stage {args.stage!r}")
    if args.teacher is not None:
        if args.stage != "binary":
            raise CliError(f"--teacher applies to --stage binary, not --stage {args.stage!r}")
        if not Path(args.teacher).is_file():
            raise CliError(f"--teacher {args.teacher!r}: no such file")
    if args.distill_scope is not None and args.teacher is None:
        raise CliError(f"--distill-scope {args.distill_scope}: needs --teacher")
    if args.distill_weight is not None:
        if args.teacher is None:
            raise CliError("--distill-weight needs --teacher")
        if not 0 < args.distill_weight < math.inf:
            raise CliError(f"--distill-weight {args.distill_weight}: must be > 0 and finite")
    parse_lr_mults(args.lr_mult)
    if args.resume and args.init:
        raise CliError("--resume and --init exclude each other")
    if args.init and not Path(args.init).is_file():
        raise CliError(f"--init {args.init!r}: no such file")


def parse_lr_mults(values: list[str]) -> tuple[tuple[str, float], ...]:
    """['segnet.corr_=10', ...] -> (('segnet.corr_', 10.0), ...); bad ones name the flag."""
    out = []
    for value in values:
        prefix, sep, mult = value.partition("=")
        try:
            m = float(mult)
        except ValueError:
            m = math.nan
        if not sep or not prefix or not 0 < m < math.inf:
            raise CliError(f"--lr-mult {value!r}: expected PREFIX=M with a parameter-name prefix and M > 0, finite")
        if prefix in dict(out):
            raise CliError(f"--lr-mult {value!r}: prefix {prefix!r} given twice")
        out.append((prefix, m))
    return tuple(out)
