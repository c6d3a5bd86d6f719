"""Pairs that span several of the network's frame intervals (time compressed), as the
geofence controller's frame stride feeds them: `bittc train --frame-stride` and `bittc
eval --data --frame-stride`."""

from __future__ import annotations

import dataclasses

import pytest

from bittc_core.data.synthetic import SyntheticPairs
from bittc_core.errors import CliError, ConfigError
from bittc_core.estimator import OracleEstimator
from bittc_core.model import BinaryTTCNet, get_config
from sim.cli.train_flags import check_train_flags
from tests.train_helpers import SMALL, cli_args


def _splits_at(monkeypatch, dt_s: float):
    import bittc_core.train.data as data

    pairs = SyntheticPairs(2, dataclasses.replace(SMALL, dt_s=dt_s), seed=0)
    monkeypatch.setattr(data, "open_split", lambda *a, **k: pairs)


@pytest.mark.parametrize("stride", [1, 3])
def test_train_takes_pairs_that_span_its_frame_stride(tmp_path, monkeypatch, stride):
    from sim.cli.train_setup import open_splits

    _splits_at(monkeypatch, 0.1 * stride)
    args = cli_args(tmp_path, "--frame-stride", str(stride))
    train, val = open_splits(args, BinaryTTCNet(get_config("tiny")))
    assert float(train[0]["dt_s"]) == pytest.approx(0.1 * stride)


def test_train_refuses_pairs_that_do_not_span_its_frame_stride(tmp_path, monkeypatch):
    from sim.cli.train_setup import open_splits

    _splits_at(monkeypatch, 0.3)
    net = BinaryTTCNet(get_config("tiny"))
    with pytest.raises(CliError, match=r"dt_s = 0.3 s, but config 'tiny' is trained at frame_dt_s = 0.1 s$"):
        open_splits(cli_args(tmp_path), net)
    with pytest.raises(CliError, match=r"--frame-stride 2 asks for 0.2 s"):
        open_splits(cli_args(tmp_path, "--frame-stride", "2"), net)


def test_train_refuses_a_frame_stride_below_one(tmp_path):
    with pytest.raises(CliError, match=r"--frame-stride 0: must be > 0"):
        check_train_flags(cli_args(tmp_path, "--frame-stride", "0"))


def test_dataset_evaluation_reads_pairs_at_a_frame_stride():
    from bittc_core.dataset_eval import evaluate

    pairs = SyntheticPairs(2, dataclasses.replace(SMALL, dt_s=0.3), seed=0)
    oracle = OracleEstimator(dt_s=0.1)
    result = evaluate(oracle, pairs, limit=None, frame_stride=3)
    assert result["pairs"] == 2 and result["miou"] == pytest.approx(1.0)  # exact fences read at eta
    with pytest.raises(ConfigError, match=r"sample 0: dt_s=0.3 s but the estimator works at 0.1 s x frame stride 2"):
        evaluate(oracle, pairs, limit=None, frame_stride=2)


def test_eval_refuses_a_frame_stride_for_a_kitti_drive(tmp_path, capsys):
    from sim.cli import main

    out = tmp_path / "o.json"
    argv = ["eval", "--kitti-raw", str(tmp_path), "--frame-stride", "2", "--method", "flow", "--out", str(out)]
    assert main(argv) == 2
    assert "--frame-stride applies to --scenarios or --data" in capsys.readouterr().err and not out.exists()
