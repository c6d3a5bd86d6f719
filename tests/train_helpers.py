"""Small trainers shared by the training tests: a tiny network on synthetic pairs."""

from __future__ import annotations

import argparse

import torch

from bittc_core.checkpoint import make_payload, save_checkpoint
from bittc_core.data.synthetic import SyntheticConfig, SyntheticPairs
from bittc_core.model import BinaryTTCNet, get_config
from bittc_core.train import RunPaths, TrainConfig, Trainer

SMALL = SyntheticConfig(height_px=48, width_px=96, patch_half_size_px=(6.0, 20.0), max_translation_px=6.0)


def saved_checkpoint(path, name: str, seed: int) -> tuple[str, dict]:
    """A checkpoint of config ``name`` at ``path``, weights drawn with ``seed``, with
    trained-looking batch-norm statistics (not the fresh 0 / 1, distinct per seed) and
    ContRefineNet's last layer (zero at init) given weights -> (its path, its state dict)."""
    torch.manual_seed(seed)
    net = BinaryTTCNet(get_config(name))
    for m in net.modules():
        if isinstance(m, torch.nn.BatchNorm2d):
            m.running_mean.uniform_(-1, 1)
            m.num_batches_tracked.fill_(seed + 1)
    torch.nn.init.uniform_(net.cont_refine.out.weight, -0.1, 0.1)
    save_checkpoint(path, make_payload(net, name, {"seed": seed}))
    return str(path), net.state_dict()


def make_trainer(
    tmp_path, stage: str = "binary", steps: int = 30, *, net_seed: int = 0, teacher: BinaryTTCNet | None = None, **kw
) -> Trainer:
    """A trainer of a ``tiny`` network (weights drawn with ``net_seed``) on 16 synthetic pairs."""
    kw.setdefault("val_every", steps)
    cfg = TrainConfig(stage=stage, steps=steps, batch_size=4, lr=3e-3, warmup_steps=3, val_limit=4, log_every=5, **kw)
    torch.manual_seed(net_seed)
    net = BinaryTTCNet(get_config("tiny"))
    return Trainer(
        net,
        "tiny",
        cfg,
        SyntheticPairs(16, SMALL, seed=1),
        SyntheticPairs(4, SMALL, seed=2),
        torch.device("cpu"),
        RunPaths.from_out(tmp_path / "m.pt"),
        teacher=teacher,
    )


def fit_fixed_batch(tr: Trainer, batch: dict, steps: int) -> list[float]:
    """``steps`` optimiser steps on one batch with the same hypotheses each step; the losses."""
    losses = []
    for step in range(steps):
        for g in tr.opt.param_groups:
            g["lr"] = tr.lr_at(step) * g["lr_mult"]
        tr.gen.manual_seed(0)  # same hypotheses each step
        loss = tr.losses(batch)["loss"]
        tr.opt.zero_grad()
        loss.backward()
        tr.opt.step()
        losses.append(loss.item())
    return losses


def cli_args(tmp_path, *extra) -> argparse.Namespace:
    """``bittc train`` arguments for a 2-step run of ``tiny`` on the synthetic pairs, plus ``extra``."""
    from sim.cli import train_cmd

    parser = argparse.ArgumentParser()
    train_cmd.add_parser(parser.add_subparsers())
    return parser.parse_args(
        [
            "train",
            "--data",
            "synthetic",
            "--config",
            "tiny",
            "--out",
            str(tmp_path / "m.pt"),
            "--steps",
            "2",
            "--val-every",
            "2",
            "--val-limit",
            "2",
            "--batch-size",
            "2",
            "--device",
            "cpu",
            *extra,
        ]
    )
