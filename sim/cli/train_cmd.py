"""`bittc train --data DIR --config NAME --out CKPT`: train the Binary-TTC network.

Writes beside CKPT: CKPT (best by val mIoU), <stem>.last.pt (resumable), <stem>.csv
(log), <stem>.config.yaml (resolved config) and, with --keep-checkpoints, the weights of
every validation step as <stem>.<stage>.step<NNNNNN>.pt. ``--stage all`` runs flow, binary and
continuous in turn, ``--steps`` each, weights carried over.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

from bittc_core.atomic import write_text_atomic
from bittc_core.errors import CliError
from sim.cli.train_flags import STAGE_CHOICES, add_train_flags, check_train_flags, parse_lr_mults
from sim.cli.train_resume import check_paths, stages_to_run
from sim.cli.train_setup import networks, open_splits, stage_configs

__all__ = ["STAGE_CHOICES", "add_parser", "parse_lr_mults", "run", "write_yaml_atomic"]


def add_parser(sub) -> argparse.ArgumentParser:
    p = sub.add_parser("train", help="train the Binary-TTC network", description=__doc__.split("\n\n", 1)[1])
    add_train_flags(p)
    return p


def write_yaml_atomic(path: Path, data: dict) -> None:
    import yaml

    write_text_atomic(path, yaml.safe_dump(data, sort_keys=False))


def run(args) -> int:
    check_train_flags(args)
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

    check_paths(args, paths)
    net, teacher, distill_weight, device = networks(args)
    lr_mults = parse_lr_mults(args.lr_mult)
    train_set, val_set = open_splits(args, net)
    stages, resume_stage = stages_to_run(args, paths, distill_weight, lr_mults)
    stage_cfgs = stage_configs(args, net, stages, lr_mults, distill_weight)
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
    meta = {
        "data": args.data,
        "seed": args.seed,
        "frame_stride": args.frame_stride,
        **({"teacher": args.teacher} if args.teacher else {}),
    }
    for stage, cfg in stage_cfgs.items():
        trainer = Trainer(net, args.config, cfg, train_set, val_set, device, paths, meta, teacher=teacher)
        if stage == resume_stage:
            trainer.resume()
        summary = trainer.run()
        print(" ".join(f"{k}={v:.4f}" if isinstance(v, float) else f"{k}={v}" for k, v in summary.items()))
    print(f"wrote {paths.best} (best), {paths.last}, {paths.csv}, {paths.config}")
    return 0
