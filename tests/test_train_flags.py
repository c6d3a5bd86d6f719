"""`bittc train`'s flags: validated before any step, a finished run not overwritten, and
each stage recorded in the run's config file as it runs."""

import argparse

import pytest

from bittc_core.errors import CliError
from sim.cli import train_cmd
from sim.cli.train_flags import check_train_flags


def args(**kw):
    base = dict(
        data="synthetic",
        config="tiny",
        out="m.pt",
        resume=False,
        init=None,
        seed=0,
        steps=10,
        batch_size=2,
        lr=3e-4,
        warmup_steps=2,
        val_every=5,
        val_limit=4,
        device="cpu",
        stage="binary",
        freeze_binary=False,
        freeze_norm_stats=False,
        actor_weight=1.0,
        inpath_weight=1.0,
        vru_weight=1.0,
        near_outside_weight=1.0,
        lovasz_weight=0.0,
        teacher=None,
        distill_weight=None,
        distill_scope=None,
        pixel_thresholds=0.0,
        inpath_thresholds=0.0,
        lr_mult=[],
        keep_checkpoints=False,
        frame_stride=1,
    )
    base.update(kw)
    return argparse.Namespace(**base)


@pytest.mark.parametrize(
    "kw, match",
    [
        (dict(config="huge"), "--config 'huge'"),
        (dict(stage="fast"), "--stage 'fast'"),
        (dict(steps=0), "--steps 0"),
        (dict(batch_size=-2), "--batch-size -2"),
        (dict(lr=5.0), "--lr 5.0"),
        (dict(warmup_steps=-1), "--warmup-steps -1"),
        (dict(out="model.bin"), "model.bin"),
        (dict(device="tpu"), "--device 'tpu'"),
        (dict(seed=-1), "--seed -1"),
        (dict(resume=True, init="x.pt"), "exclude"),
        (dict(actor_weight=0.0), "--actor-weight 0.0"),
        (dict(inpath_weight=-2.0), "--inpath-weight -2.0"),
        (dict(vru_weight=0.0), "--vru-weight 0.0"),
        (dict(near_outside_weight=-1.0), "--near-outside-weight -1.0"),
        (dict(lovasz_weight=-1.0), "--lovasz-weight -1.0"),
        (dict(freeze_binary=True), "--freeze-binary applies to the continuous stage, not --stage 'binary'"),
        (dict(freeze_norm_stats=True), "--freeze-norm-stats needs --init"),
        (dict(teacher="missing.pt"), "--teacher 'missing.pt': no such file"),
        (
            dict(teacher="missing.pt", stage="continuous"),
            "--teacher applies to --stage binary, not --stage 'continuous'",
        ),
        (dict(teacher="missing.pt", stage="all"), "--teacher applies to --stage binary, not --stage 'all'"),
        (dict(lovasz_weight=float("inf")), "--lovasz-weight inf"),
        (dict(distill_weight=0.5), "--distill-weight needs --teacher"),
        (dict(pixel_thresholds=1.5), "--pixel-thresholds 1.5"),
        (dict(pixel_thresholds=float("nan")), "--pixel-thresholds nan"),
        (dict(inpath_thresholds=-0.1), "--inpath-thresholds -0.1"),
        (dict(pixel_thresholds=0.5, inpath_thresholds=0.75), r"--inpath-thresholds 0.75: must be in \[0, 1 - --pixel"),
        (dict(lr_mult=["segnet.corr_"]), "--lr-mult 'segnet.corr_': expected PREFIX=M"),
        (dict(lr_mult=["=3"]), "--lr-mult '=3'"),
        (dict(lr_mult=["segnet.=0"]), "--lr-mult 'segnet.=0'"),
        (dict(lr_mult=["segnet.=x"]), "--lr-mult 'segnet.=x'"),
        (dict(lr_mult=["segnet.=inf"]), "--lr-mult 'segnet.=inf'"),
        (dict(lr_mult=["segnet.=2", "segnet.=3"]), "prefix 'segnet.' given twice"),
    ],
)
def test_train_flags_are_validated(kw, match):
    with pytest.raises(CliError, match=match):
        check_train_flags(args(**kw))


def test_train_cli_refuses_to_overwrite_a_run(tmp_path):
    out = tmp_path / "m.pt"
    (tmp_path / "m.last.pt").write_bytes(b"x")
    with pytest.raises(CliError, match="pass --resume"):
        train_cmd.run(args(out=str(out)))


def test_config_yaml_records_each_stage_as_it_runs(tmp_path):
    import yaml

    out = tmp_path / "m.pt"
    assert (
        train_cmd.run(
            args(
                out=str(out),
                stage="continuous",
                freeze_binary=True,
                steps=2,
                val_every=2,
                val_limit=2,
                actor_weight=2.0,
            )
        )
        == 0
    )
    saved = yaml.safe_load((tmp_path / "m.config.yaml").read_text())
    assert saved["stages"] == ["continuous"]
    cfg = saved["train_config"]["continuous"]
    assert cfg["stage"] == "continuous" and cfg["freeze_binary"] is True and cfg["actor_weight"] == 2.0
    assert cfg["freeze_norm_stats"] is False


def test_freeze_norm_stats_runs_from_init_and_keeps_its_statistics(tmp_path):
    import torch

    from bittc_core.checkpoint import load_checkpoint
    from sim.cli import main
    from tests.train_helpers import saved_checkpoint

    start, start_state = saved_checkpoint(tmp_path / "start.pt", "tiny", 0)
    out = tmp_path / "m.pt"
    flags = ["--data", "synthetic", "--config", "tiny", "--steps", "2", "--batch-size", "2", "--val-every", "1"]
    flags += ["--val-limit", "2", "--warmup-steps", "1", "--init", start, "--out", str(out)]
    assert main(["train", *flags, "--freeze-norm-stats"]) == 0
    after = load_checkpoint(out)["state_dict"]
    for key, value in start_state.items():
        if key.endswith(("running_mean", "running_var")):
            assert torch.equal(after[key], value), key
