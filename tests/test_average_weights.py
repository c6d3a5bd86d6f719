"""docs/average_weights.py: the element-wise mean of checkpoints of one config."""

import importlib.util
from pathlib import Path

import pytest
import torch

from bittc_core.checkpoint import CheckpointError, load_checkpoint, make_payload, save_checkpoint
from bittc_core.model import BinaryTTCNet, get_config

SCRIPT = Path(__file__).resolve().parents[1] / "docs" / "average_weights.py"


def load_script():
    spec = importlib.util.spec_from_file_location("average_weights", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def saved(path, name, seed):
    torch.manual_seed(seed)
    net = BinaryTTCNet(get_config(name))
    for m in net.modules():  # distinct batch-norm statistics too
        if isinstance(m, torch.nn.BatchNorm2d):
            m.running_mean.uniform_(-1, 1)
            m.num_batches_tracked.fill_(seed + 1)
    save_checkpoint(path, make_payload(net, name, {"seed": seed}))
    return str(path), net.state_dict()


def test_the_mean_of_two_checkpoints(tmp_path):
    a, sa = saved(tmp_path / "a.pt", "tiny", 0)
    b, sb = saved(tmp_path / "b.pt", "tiny", 1)
    load_script().main(str(tmp_path / "mean.pt"), a, b)
    mean = load_checkpoint(tmp_path / "mean.pt", expected_config="tiny")
    for key, value in mean["state_dict"].items():
        if value.is_floating_point():
            torch.testing.assert_close(value, 0.5 * (sa[key] + sb[key]))
        else:
            assert torch.equal(value, sa[key])  # counters from the first
    assert any(not torch.equal(sa[k], sb[k]) for k in sa if sa[k].is_floating_point())  # a real average
    assert [m["path"] for m in mean["train_meta"]["average_of"]] == [a, b]
    BinaryTTCNet(get_config("tiny")).load_state_dict(mean["state_dict"])


def test_checkpoints_of_different_configs_are_refused(tmp_path):
    a, _ = saved(tmp_path / "a.pt", "tiny", 0)
    b, _ = saved(tmp_path / "b.pt", "cpu-small", 1)
    with pytest.raises(CheckpointError, match="only checkpoints of one config can be averaged"):
        load_script().main(str(tmp_path / "mean.pt"), a, b)
    assert not (tmp_path / "mean.pt").exists()
