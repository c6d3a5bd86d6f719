"""`bittc train --data DIR --config NAME --out CKPT`: train the Binary-TTC network.

Writes beside CKPT: CKPT (best by val mIoU), <stem>.last.pt (resumable), <stem>.csv
(log), <stem>.config.yaml (resolved config) and, with --keep-checkpoints, the weights of
every validation step as <stem>.<stage>.step<NNNNNN>.pt. ``--stage all`` runs flow, binary and
continuous in turn, ``--steps`` each, weights carried over.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
from pathlib import Path

from bittc_core.atomic import write_text_atomic
from bittc_core.errors import CliError, ConfigError
from sim.cli.common import add_device_flag, add_seed_flag, check_device, check_seed, flag_error

STAGE_CHOICES = ("flow", "binary", "continuous", "all")


def add_parser(sub) -> argparse.ArgumentParser:
    p = sub.add_parser("train", help="train the Binary-TTC network", description=__doc__.split("\n\n", 1)[1])
    p.add_argument("--data", required=True, help="dataset folder, or 'synthetic' for the built-in generator")
    p.add_argument(
        "--config",
        required=True,
        help="model config name (paper, cpu-small, cpu-small-gc, cpu-medium, cpu-small-corr, cpu-small-corr-gc, tiny)",
    )
    p.add_argument("--out", required=True, help="best checkpoint path, *.pt")
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
    return p


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
        help="with --teacher: weight of the distillation BCE beside the ground-truth BCE (default 1)",
    )
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


def _check(args) -> None:
    from bittc_core.model import CONFIGS

    if args.config not in CONFIGS:
        raise CliError(f"--config {args.config!r}: expected one of {sorted(CONFIGS)}")
    if args.stage not in STAGE_CHOICES:
        raise CliError(f"--stage {args.stage!r}: expected one of {STAGE_CHOICES}")
    check_device(args.device)
    for flag, value in (
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
    if not 0 <= args.lovasz_weight < math.inf:
        raise CliError(f"--lovasz-weight {args.lovasz_weight}: must be >= 0 and finite")
    if not 0 <= args.pixel_thresholds <= 1:
        raise CliError(f"--pixel-thresholds {args.pixel_thresholds}: must be in [0, 1]")
    if not 0 <= args.inpath_thresholds <= 1 - args.pixel_thresholds:
        raise CliError(
            f"--inpath-thresholds {args.inpath_thresholds}: must be in [0, 1 - --pixel-thresholds "
            f"= {1 - args.pixel_thresholds:g}]"
        )
    if args.freeze_binary and args.stage not in ("continuous", "all"):
        raise CliError(f"--freeze-binary applies to the continuous stage, not --stage {args.stage!r}")
    if args.teacher is not None:
        if args.stage != "binary":
            raise CliError(f"--teacher applies to --stage binary, not --stage {args.stage!r}")
        if not Path(args.teacher).is_file():
            raise CliError(f"--teacher {args.teacher!r}: no such file")
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


def _check_same_lr_mults(name: str, meta: dict, lr_mults: tuple[tuple[str, float], ...]) -> None:
    """A resumed run keeps its learning-rate multipliers (its optimizer's groups)."""
    old = tuple((str(p), float(m)) for p, m in meta.get("train_config", {}).get("lr_mults", ()))
    if sorted(old) != sorted(lr_mults):  # the groups do not depend on the flags' order

        def show(mults):
            return " ".join(f"--lr-mult {p}={m:g}" for p, m in mults) or "no --lr-mult"

        raise CliError(f"--resume: {name} was trained with {show(old)}, not {show(lr_mults)}")


def _check_same_teacher(name: str, meta: dict, teacher: str | None, distill_weight: float) -> None:
    """A resumed run keeps the teacher and distillation weight it was started with."""
    old_teacher = meta.get("teacher")
    old_weight = float(meta.get("train_config", {}).get("distill_weight", 0.0))
    same = (
        (old_teacher is None) == (teacher is None)
        and old_weight == distill_weight
        and (teacher is None or Path(old_teacher).resolve() == Path(teacher).resolve())
    )
    if not same:
        raise CliError(
            f"--resume: {name} was trained with --teacher {old_teacher!r} (distill weight {old_weight:g}), "
            f"not --teacher {teacher!r} (distill weight {distill_weight:g})"
        )


def write_yaml_atomic(path: Path, data: dict) -> None:
    import yaml

    write_text_atomic(path, yaml.safe_dump(data, sort_keys=False))


def run(args) -> int:
    _check(args)
    from bittc_core.parallel import OutputLock
    from bittc_core.train import RunPaths

    paths = RunPaths.from_out(args.out)
    lock = OutputLock(paths.best.parent, what="--out", name=f".{paths.best.stem}.lock")
    try:
        paths.best.parent.mkdir(parents=True, exist_ok=True)
        lock.acquire()  # a second training into the same --out is refused with the holder's pid
    except OSError as err:
        raise CliError(f"--out {args.out!r}: cannot create its folder ({err})") from None
    with lock:  # acquired above; released, and discarded when the run is refused, on the way out
        return _train(args, paths)


def _train(args, paths) -> int:
    """The run behind ``run``, with this run's output locked: check, build, then train stage by stage."""
    from bittc_core.train import Trainer

    _check_paths(args, paths)
    net, teacher, distill_weight, device = _networks(args)
    lr_mults = parse_lr_mults(args.lr_mult)
    train_set, val_set = _open_splits(args, net)
    stages, resume_stage = _stages(args, paths, distill_weight, lr_mults)
    stage_cfgs = _stage_configs(args, net, stages, lr_mults, distill_weight)
    write_yaml_atomic(
        paths.config,
        {
            "argv": list(sys.argv),
            "data": args.data,
            "device": str(device),
            "stages": stages,
            "model_config_name": args.config,
            "teacher": args.teacher,
            "model_config": dataclasses.asdict(net.config),
            "train_config": {stage: dataclasses.asdict(cfg) for stage, cfg in stage_cfgs.items()},  # as each stage runs
        },
    )
    meta = {"data": args.data, "seed": args.seed, **({"teacher": args.teacher} if args.teacher else {})}
    for stage, cfg in stage_cfgs.items():
        trainer = Trainer(net, args.config, cfg, train_set, val_set, device, paths, meta, teacher=teacher)
        if stage == resume_stage:
            trainer.resume()
        summary = trainer.run()
        print(" ".join(f"{k}={v:.4f}" if isinstance(v, float) else f"{k}={v}" for k, v in summary.items()))
    print(f"wrote {paths.best} (best), {paths.last}, {paths.csv}, {paths.config}")
    return 0


def _check_paths(args, paths) -> None:
    if args.resume and not paths.last.is_file():
        raise CliError(f"--resume: no resumable checkpoint at {str(paths.last)!r}")
    if not args.resume and (paths.last.exists() or paths.csv.exists()):
        raise CliError(
            f"--out {args.out!r}: a run already exists there ({paths.last.name}); pass --resume or choose another --out"
        )
    if args.teacher and Path(args.teacher).resolve() in (paths.best.resolve(), paths.last.resolve()):
        raise CliError(f"--teacher {args.teacher!r}: is this run's own checkpoint (--out {args.out!r} writes it)")


def _networks(args):
    """-> (the network to train, the teacher or None, the distillation weight, the device)."""
    import torch

    from bittc_core.checkpoint import build_network, init_network, load_checkpoint, pick_device
    from bittc_core.model import BinaryTTCNet, get_config

    try:
        device = pick_device(args.device)
        torch.manual_seed(args.seed)
        net = init_network(args.init, args.config) if args.init else BinaryTTCNet(get_config(args.config))
    except ConfigError as e:
        raise flag_error(e, {"device": "--device", "initial checkpoint": "--init"}) from None
    teacher, distill_weight = None, 0.0
    if args.teacher:
        distill_weight = args.distill_weight or 1.0
        teacher = build_network(load_checkpoint(args.teacher, map_location="cpu"))
        if teacher.config != net.config:
            raise CliError(f"--teacher {args.teacher!r}: its model config differs from --config {args.config!r}")
    return net, teacher, distill_weight, device


def _open_splits(args, net):
    """-> (train, val) datasets, refused when their frame interval is not the config's."""
    from bittc_core.train.data import open_split

    try:
        train_set = open_split(args.data, "train", augment=True, seed=args.seed)
        val_set = open_split(args.data, "val", seed=args.seed)
    except ConfigError as e:
        raise flag_error(e, {"dataset": "--data"}) from None
    for name, ds in (("train", train_set), ("val", val_set)):
        dt = float(ds[0]["dt_s"])
        if abs(dt - net.config.frame_dt_s) > 1e-6:
            raise CliError(
                f"--data {args.data!r}: the {name} split has frame interval dt_s = {dt:g} s, but config "
                f"{args.config!r} is trained at frame_dt_s = {net.config.frame_dt_s:g} s"
            )
    return train_set, val_set


def _stages(args, paths, distill_weight, lr_mults) -> tuple[list[str], str | None]:
    """-> (the stages to run, the stage a --resume continues or None)."""
    from bittc_core.checkpoint import load_checkpoint
    from bittc_core.train import STAGES

    stages = list(STAGES) if args.stage == "all" else [args.stage]
    if not args.resume:
        return stages, None
    last = load_checkpoint(paths.last, map_location="cpu", expected_config=args.config)
    state, meta_last = last.get("train_state", {}), last.get("train_meta", {})
    resume_stage = state.get("stage")
    _check_same_teacher(paths.last.name, meta_last, args.teacher, distill_weight)
    _check_same_lr_mults(paths.last.name, meta_last, lr_mults)
    if resume_stage not in stages:
        raise CliError(f"--resume: {paths.last.name} is at stage {resume_stage!r}, not in {stages}")
    return stages[stages.index(resume_stage) :], resume_stage


def _stage_configs(args, net, stages, lr_mults, distill_weight) -> dict:
    """stage -> its TrainConfig, each checked against the network before anything is written."""
    from bittc_core.train import TrainConfig
    from bittc_core.train.params import frozen_prefixes, param_groups

    base = TrainConfig(
        steps=args.steps,
        batch_size=args.batch_size,
        lr=args.lr,
        warmup_steps=args.warmup_steps,
        val_every=args.val_every,
        val_limit=args.val_limit,
        seed=args.seed,
        actor_weight=args.actor_weight,
        inpath_weight=args.inpath_weight,
        lovasz_weight=args.lovasz_weight,
        distill_weight=distill_weight,
        pixel_threshold_share=args.pixel_thresholds,
        inpath_threshold_share=args.inpath_thresholds,
        lr_mults=lr_mults,
        keep_checkpoints=args.keep_checkpoints,
    )
    stage_cfgs = {
        stage: dataclasses.replace(base, stage=stage, freeze_binary=args.freeze_binary and stage == "continuous")
        for stage in stages
    }
    for stage, cfg in stage_cfgs.items():  # before anything is written or trained
        try:
            param_groups(net, lr_mults, frozen_prefixes(cfg))
        except ValueError as err:
            frozen = " --freeze-binary" if cfg.freeze_binary else ""
            raise CliError(f"--lr-mult: {err} (config {args.config!r}, --stage {stage}{frozen})") from None
    return stage_cfgs
