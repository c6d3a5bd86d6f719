"""What a `bittc train` run trains: the network (and teacher), the dataset splits and each stage's config."""

from __future__ import annotations

import dataclasses

from bittc_core.errors import CliError, ConfigError
from sim.cli.common import flag_error


def networks(args):
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


def open_splits(args, net):
    """-> (train, val) datasets, refused when their frame interval is not the config's times
    ``--frame-stride``: the labels are scale ratios (eta) of the pair, so a pair N network
    intervals long teaches the network to read eta on such pairs, at its own interval."""
    from bittc_core.train.data import open_split
    from bittc_core.ttc import pair_spans_stride

    try:
        train_set = open_split(args.data, "train", augment=True, seed=args.seed)
        val_set = open_split(args.data, "val", seed=args.seed)
    except ConfigError as e:
        raise flag_error(e, {"dataset": "--data"}) from None
    for name, ds in (("train", train_set), ("val", val_set)):
        dt = float(ds[0]["dt_s"])
        if not pair_spans_stride(dt, net.config.frame_dt_s, args.frame_stride):
            want = args.frame_stride * net.config.frame_dt_s
            raise CliError(
                f"--data {args.data!r}: the {name} split has frame interval dt_s = {dt:g} s, but config "
                f"{args.config!r} is trained at frame_dt_s = {net.config.frame_dt_s:g} s"
                + (f" and --frame-stride {args.frame_stride} asks for {want:g} s" if args.frame_stride != 1 else "")
            )
    if args.distill_scope == "scenery-vehicles" and "actor_class" not in train_set[0]:
        raise CliError(
            f"--distill-scope scenery-vehicles: --data {args.data!r} has no actor classes (pedestrians, cyclists) "
            "to keep the ground truth of"
        )
    return train_set, val_set


def stage_configs(args, net, stages, lr_mults, distill_weight) -> dict:
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
        vru_weight=args.vru_weight,
        near_outside_weight=args.near_outside_weight,
        lovasz_weight=args.lovasz_weight,
        distill_weight=distill_weight,
        distill_scope=args.distill_scope or "all",
        pixel_threshold_share=args.pixel_thresholds,
        inpath_threshold_share=args.inpath_thresholds,
        lr_mults=lr_mults,
        keep_checkpoints=args.keep_checkpoints,
        freeze_norm_stats=args.freeze_norm_stats,
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
