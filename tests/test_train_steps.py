"""Training: a few steps lower the loss; resume restores the state (the flags: test_train_flags.py)."""

import argparse
import dataclasses

import pytest
import torch

from bittc_core.train import TrainConfig
from bittc_core.train.losses import masked_bce
from bittc_core.train.losses_stage import stage_losses
from bittc_core.train.targets import (
    eta_labels,
    near_outside,
    valid_mask,
)
from sim.cli import train_cmd
from tests.train_helpers import cli_args, fit_fixed_batch, make_trainer


@pytest.mark.parametrize(
    "stage, actor_weight, lovasz_weight, pixel_share",
    [
        ("flow", 1.0, 0.0, 0.0),
        ("binary", 1.0, 0.0, 0.0),
        ("binary", 3.0, 0.0, 0.0),
        ("binary", 1.0, 0.5, 0.0),
        ("binary", 1.0, 0.0, 0.5),
    ],
)
def test_a_few_steps_lower_the_loss(tmp_path, stage, actor_weight, lovasz_weight, pixel_share):
    tr = make_trainer(
        tmp_path, stage, actor_weight=actor_weight, lovasz_weight=lovasz_weight, pixel_threshold_share=pixel_share
    )
    losses = fit_fixed_batch(tr, next(iter(tr.loader)), 30)  # one fixed batch: the loss must go down on it
    assert sum(losses[-3:]) / 3 < 0.8 * sum(losses[:3]) / 3, losses


def test_continuous_stage_loss_is_finite_and_differentiable(tmp_path):
    tr = make_trainer(tmp_path, "continuous")
    parts = tr.losses(next(iter(tr.loader)))
    assert torch.isfinite(parts["loss"]) and parts["cont"] > 0
    parts["loss"].backward()


def test_frozen_continuous_stage_trains_the_continuous_refiner_only(tmp_path):
    tr = make_trainer(tmp_path, "continuous", steps=3, freeze_binary=True)
    frozen = {k: v.clone() for k, v in tr.net.state_dict().items() if not k.startswith("cont_refine.")}
    refiner = {k: v.clone() for k, v in tr.net.cont_refine.state_dict().items()}
    summary = tr.run()
    assert summary["best_val_mid"] == pytest.approx(summary["val_mid"])  # one validation, kept by MiD
    after = tr.net.state_dict()
    for k, v in frozen.items():  # weights and batch-norm statistics of the binary network
        assert torch.equal(after[k], v), k
    assert any(not torch.equal(tr.net.cont_refine.state_dict()[k], v) for k, v in refiner.items())
    with pytest.raises(ValueError, match="not 'binary'"):
        TrainConfig(stage="binary", freeze_binary=True)


@pytest.mark.parametrize("freeze", [False, True])
def test_frozen_norm_statistics_stay_put_while_the_weights_learn(tmp_path, freeze):
    # a validation after every step: training mode must come back without the statistics' updates
    tr = make_trainer(tmp_path, "binary", steps=3, val_every=1, freeze_norm_stats=freeze)
    before = {k: v.clone() for k, v in tr.net.state_dict().items()}
    stats = [k for k in before if k.endswith(("running_mean", "running_var"))]
    assert stats
    tr.run()
    after = tr.net.state_dict()
    moved = [k for k in stats if not torch.equal(after[k], before[k])]
    binary = [k for k in stats if k.startswith(("features.", "segnet."))]  # what the binary stage runs
    assert binary
    assert (moved == []) if freeze else set(binary) <= set(moved), moved
    # the norms' scale and shift learn either way
    scales = [k[: -len("running_mean")] + "weight" for k in binary if k.endswith("running_mean")]
    assert all(not torch.equal(after[k], before[k]) for k in scales)


def test_train_config_refuses_a_negative_warmup():
    with pytest.raises(ValueError, match="warmup_steps=-1"):
        TrainConfig(warmup_steps=-1)


def test_run_writes_outputs_and_resume_restores_state(tmp_path):
    tr = make_trainer(tmp_path, "binary", steps=4)
    summary = tr.run()
    paths = tr.paths
    assert paths.best.is_file() and paths.last.is_file() and paths.csv.is_file()
    assert summary["steps"] == 4 and 0.0 <= summary["best_val_miou"] <= 1.0
    again = make_trainer(tmp_path, "binary", steps=4)
    again.resume()
    assert again.step == 4 and again.best == pytest.approx(tr.best)
    assert torch.equal(again.gen.get_state(), tr.gen.get_state())
    for a, b in zip(again.net.state_dict().values(), tr.net.state_dict().values()):
        assert torch.equal(a, b)
    wrong = make_trainer(tmp_path, "flow", steps=4)
    with pytest.raises(ValueError, match="stage 'binary', not 'flow'"):
        wrong.resume()


def test_keep_checkpoints_keeps_the_weights_of_every_validation(tmp_path):
    from bittc_core.checkpoint import load_checkpoint

    tr = make_trainer(tmp_path, "binary", steps=4, keep_checkpoints=True)
    tr.cfg = dataclasses.replace(tr.cfg, val_every=2)
    tr.run()
    kept = sorted(p.name for p in tmp_path.glob("m.binary.step*.pt"))
    assert kept == ["m.binary.step000002.pt", "m.binary.step000004.pt"]
    last = load_checkpoint(tmp_path / "m.binary.step000004.pt")
    assert last["train_meta"]["step"] == 4 and "train_state" not in last
    for k, v in tr.net.state_dict().items():  # the network as it ended
        assert torch.equal(last["state_dict"][k], v), k
    first = load_checkpoint(tmp_path / "m.binary.step000002.pt")
    assert any(not torch.equal(first["state_dict"][k], v) for k, v in last["state_dict"].items())
    cli = tmp_path / "cli"
    assert train_cmd.run(cli_args(cli, "--keep-checkpoints")) == 0  # the flag reaches the trainer
    assert [p.name for p in cli.glob("*.step*.pt")] == ["m.binary.step000002.pt"]
    plain = make_trainer(tmp_path / "plain", "binary", steps=2)
    plain.run()
    assert not list((tmp_path / "plain").glob("*.step*.pt"))


def test_resume_drops_the_log_rows_it_will_redo(tmp_path):
    import csv

    tr = make_trainer(tmp_path, "binary", steps=4)
    tr.run()  # the resumable checkpoint is at step 4
    with open(tr.paths.csv, "a", newline="") as f:  # a run killed later logged steps it never saved
        f.write("5,binary,0.1\n6,binary,0.1\n9,flow,0.2\n")
    again = make_trainer(tmp_path, "binary", steps=6)
    again.resume()
    rows = list(csv.DictReader(open(tr.paths.csv)))
    assert [(r["stage"], r["step"]) for r in rows] == [("binary", "4"), ("flow", "9")]
    again.run()
    assert [r["step"] for r in csv.DictReader(open(tr.paths.csv)) if r["stage"] == "binary"] == ["4", "5", "6"]


def _record_batches(tr, seen: list, interrupt_at: int | None = None) -> None:
    """Keep a copy of every batch ``tr`` trains on; raise KeyboardInterrupt in step ``interrupt_at``."""
    losses = tr.losses

    def spy(batch):
        seen.append(batch["image_prev"].clone())
        if len(seen) == interrupt_at:
            raise KeyboardInterrupt
        return losses(batch)

    tr.losses = spy


def test_resume_continues_the_interrupted_epoch_in_the_same_order(tmp_path):
    # 16 pairs in batches of 4: 4 steps an epoch; checkpoints every 3 steps
    def trainer(folder):
        tr = make_trainer(tmp_path / folder, "binary", steps=8)
        tr.cfg = dataclasses.replace(tr.cfg, val_every=3)
        return tr

    full, seen_full = trainer("full"), []
    _record_batches(full, seen_full)
    full.run()
    cut, seen_cut = trainer("cut"), []
    _record_batches(cut, seen_cut, interrupt_at=7)
    with pytest.raises(KeyboardInterrupt):  # killed in step 7, after the checkpoint of step 6
        cut.run()
    resumed, seen_resumed = trainer("cut"), []
    resumed.resume()
    assert resumed.step == 6  # mid-way through the second epoch
    _record_batches(resumed, seen_resumed)
    resumed.run()
    assert len(seen_full) == 8 and len(seen_resumed) == 2
    for a, b in zip(seen_cut[:6] + seen_resumed, seen_full, strict=True):
        assert torch.equal(a, b)
    assert not torch.equal(torch.stack(seen_full[:4]), torch.stack(seen_full[4:8]))  # epochs are reshuffled


def test_seconds_per_step_leave_validation_out(tmp_path, monkeypatch):
    import csv
    import time

    import bittc_core.train.loop as loop_mod

    pause_s = 0.6
    real = loop_mod.validate

    def slow_validate(*args, **kw):
        time.sleep(pause_s)
        return real(*args, **kw)

    monkeypatch.setattr(loop_mod, "validate", slow_validate)
    tr = make_trainer(tmp_path, "binary", steps=6)
    tr.cfg = dataclasses.replace(tr.cfg, val_every=3, log_every=1)
    tr.run()
    per_step = {int(r["step"]): float(r["s_per_step"]) for r in csv.DictReader(open(tr.paths.csv))}
    assert sorted(per_step) == [1, 2, 3, 4, 5, 6]
    assert max(per_step.values()) < pause_s, per_step  # step 4 follows the validation of step 3


def test_actor_weight_help_names_every_vehicle_pixel_not_only_moving_ones():
    train = train_cmd.add_parser(argparse.ArgumentParser().add_subparsers())
    help_text = next(a.help for a in train._actions if "--actor-weight" in a.option_strings)
    # the weight applies to instance > 0: parked and stationary vehicles too
    assert "moving-actor" not in help_text and "moving or not" in help_text, help_text


def test_the_near_outside_weight_weights_scenery_just_outside_each_fence(tmp_path):
    tr = make_trainer(tmp_path, near_outside_weight=4.0)
    batch = next(iter(tr.loader))
    seen = []
    real = tr.net.classify_eta
    tr.net.classify_eta = lambda ctx, feats, thr: seen.append((thr, real(ctx, feats, thr))) or seen[-1][1]
    out = stage_losses(tr.net, tr.cfg, batch, torch.Generator().manual_seed(0), torch.device("cpu"))
    ((thr, logits),) = seen
    eta = batch["eta"]
    near = near_outside(eta, thr) & (batch["instance"] == 0)[:, None]
    assert near.any()
    expect = masked_bce(logits, eta_labels(eta, thr), valid_mask(batch)[:, None], torch.where(near, 4.0, 1.0))
    assert torch.allclose(out["ttc"], expect)
    with pytest.raises(ValueError, match="near_outside_weight=0"):
        TrainConfig(near_outside_weight=0)
