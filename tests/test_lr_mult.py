"""Per-module learning-rate multipliers (``bittc train --lr-mult PREFIX=M``)."""

import pytest
import torch

from bittc_core.errors import CliError
from bittc_core.model import BinaryTTCNet, get_config
from bittc_core.train import TrainConfig
from bittc_core.train.params import param_groups
from sim.cli import train_cmd
from tests.train_helpers import cli_args, fit_fixed_batch, make_trainer


def _group_of(groups, param):
    return next(g["lr_mult"] for g in groups if any(q is param for q in g["params"]))


def test_groups_cover_every_trainable_parameter_once_and_the_longest_prefix_wins():
    net = BinaryTTCNet(get_config("tiny"))
    net.features.requires_grad_(False)
    groups = param_groups(net, (("segnet.", 2.0), ("segnet.head", 5.0)))
    listed = [q for g in groups for q in g["params"]]
    trainable = [q for q in net.parameters() if q.requires_grad]
    assert len(listed) == len(trainable) and {id(q) for q in listed} == {id(q) for q in trainable}
    assert _group_of(groups, net.segnet.head.weight) == 5.0
    assert _group_of(groups, net.segnet.first_src.weight) == 2.0
    assert _group_of(groups, next(net.refine.parameters())) == 1.0
    with pytest.raises(ValueError, match=r"no trainable parameter name starts with \['features.'\]"):
        param_groups(net, (("features.", 3.0),))  # frozen: nothing to multiply
    with pytest.raises(ValueError, match="a prefix is named twice"):
        TrainConfig(lr_mults=(("segnet.", 2.0), ("segnet.", 3.0)))
    with pytest.raises(ValueError, match=r"lr_mults \('segnet.', 0.0\)"):
        TrainConfig(lr_mults=(("segnet.", 0.0),))


def test_a_multiplied_module_takes_that_multiple_of_the_step(tmp_path):
    """Adam's first step moves each weight by about lr (the sign of its gradient): with a
    multiplier of 10 the named module moves ten times as far, the others as before."""
    batch = next(iter(make_trainer(tmp_path / "a").loader))
    moved = {}
    for name, mults in (("plain", ()), ("x10", (("segnet.head", 10.0),))):
        tr = make_trainer(tmp_path / name, net_seed=0, lr_mults=mults)
        before = {k: v.detach().clone() for k, v in tr.net.named_parameters()}
        fit_fixed_batch(tr, batch, steps=1)
        moved[name] = {k: (v.detach() - before[k]).abs().max().item() for k, v in tr.net.named_parameters()}
    head, other = "segnet.head.weight", "segnet.first_src.weight"
    assert 9.0 < moved["x10"][head] / moved["plain"][head] < 11.0
    assert moved["x10"][other] == pytest.approx(moved["plain"][other], rel=1e-3)


def test_cli_refuses_a_prefix_that_names_nothing_and_writes_nothing(tmp_path):
    with pytest.raises(
        CliError, match=r"--lr-mult: .*starts with \['segnet.corr_'\] \(config 'tiny', --stage binary\)"
    ):
        train_cmd.run(cli_args(tmp_path, "--lr-mult", "segnet.corr_=10"))
    # a module the stage freezes: refused before the first stage runs
    with pytest.raises(CliError, match=r"starts with \['segnet.head'\] .*--stage continuous --freeze-binary\)"):
        train_cmd.run(cli_args(tmp_path, "--stage", "all", "--freeze-binary", "--lr-mult", "segnet.head=2"))
    assert not list(tmp_path.glob("m*"))


def test_run_records_the_multipliers_and_resume_keeps_them(tmp_path):
    import yaml

    assert train_cmd.run(cli_args(tmp_path, "--lr-mult", "segnet.head=4")) == 0
    saved = yaml.safe_load((tmp_path / "m.config.yaml").read_text())
    assert saved["train_config"]["binary"]["lr_mults"] == [["segnet.head", 4.0]]
    for extra, match in (
        (["--resume"], "with --lr-mult segnet.head=4, not no --lr-mult"),
        (["--resume", "--lr-mult", "segnet.head=2"], "not --lr-mult segnet.head=2"),
    ):
        with pytest.raises(CliError, match=match):
            train_cmd.run(cli_args(tmp_path, *extra))
    assert train_cmd.run(cli_args(tmp_path, "--resume", "--lr-mult", "segnet.head=4", "--steps", "3")) == 0


def test_resume_accepts_the_flags_in_another_order(tmp_path):
    flags = ["--lr-mult", "segnet.head=4", "--lr-mult", "refine.=2"]
    assert train_cmd.run(cli_args(tmp_path, *flags)) == 0
    assert train_cmd.run(cli_args(tmp_path, "--resume", *flags[2:], *flags[:2], "--steps", "3")) == 0


def test_the_training_loop_sets_each_groups_rate(tmp_path):
    """Trainer.run itself (not a test helper) scales the scheduled rate per group."""
    tr = make_trainer(tmp_path, steps=1, lr_mults=(("segnet.head", 10.0),))
    tr.run()
    rates = {g["lr_mult"]: g["lr"] for g in tr.opt.param_groups}
    assert set(rates) == {1.0, 10.0} and rates[10.0] == pytest.approx(10 * rates[1.0])
    assert rates[1.0] == pytest.approx(tr.lr_at(0))


def test_a_run_saved_before_multipliers_existed_resumes(tmp_path):
    """Resumable checkpoints written before ``lr_mults`` hold optimizer groups without an
    ``lr_mult``: they resume at 1x."""
    tr = make_trainer(tmp_path, steps=2)
    tr.run()
    ckpt = torch.load(tr.paths.last, map_location="cpu", weights_only=True)
    for group in ckpt["train_state"]["optimizer"]["param_groups"]:
        del group["lr_mult"]
    torch.save(ckpt, tr.paths.last)
    again = make_trainer(tmp_path, steps=4)
    again.resume()
    assert again.run()["steps"] == 4
