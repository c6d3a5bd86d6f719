"""`bittc weights average|zero`: the mean of checkpoints of one config, and an ablation copy;
and the grown copy the weight recipes train from (``checkpoint_ops.grown_payload``)."""

import pytest
import torch

from bittc_core.checkpoint import CheckpointError, load_checkpoint, save_checkpoint
from bittc_core.checkpoint_ops import average_checkpoints, grown_payload, zero_layers
from bittc_core.model import BinaryTTCNet, get_config
from sim.cli import main
from tests.train_helpers import saved_checkpoint


def test_the_mean_of_two_checkpoints(tmp_path):
    a, sa = saved_checkpoint(tmp_path / "a.pt", "tiny", 0)
    b, sb = saved_checkpoint(tmp_path / "b.pt", "tiny", 1)
    assert main(["weights", "average", a, b, "--out", str(tmp_path / "mean.pt")]) == 0
    mean = load_checkpoint(tmp_path / "mean.pt", expected_config="tiny")
    for key, value in mean["state_dict"].items():
        if value.is_floating_point():
            torch.testing.assert_close(value, 0.5 * (sa[key] + sb[key]))
        else:
            assert torch.equal(value, sa[key])  # counters from the first
    assert any(not torch.equal(sa[k], sb[k]) for k in sa if sa[k].is_floating_point())  # a real average
    assert [m["path"] for m in mean["train_meta"]["average_of"]] == [a, b]
    BinaryTTCNet(get_config("tiny")).load_state_dict(mean["state_dict"])


def test_a_checkpoint_saved_before_a_config_field_existed_averages_with_a_newer_one(tmp_path):
    a, sa = saved_checkpoint(tmp_path / "a.pt", "cpu-small-corr", 0)
    b, sb = saved_checkpoint(tmp_path / "b.pt", "cpu-small-corr", 1)
    old = torch.load(a, weights_only=True)
    for field in ("corr_column", "column_input"):  # growth fields added later, at their defaults
        del old["config"][field]
    torch.save(old, a)
    mean = average_checkpoints([a, b])
    assert mean["config"] == load_checkpoint(b)["config"]  # the full config, as loaded
    key = "segnet.first_ref.weight"
    torch.testing.assert_close(mean["state_dict"][key], 0.5 * (sa[key] + sb[key]))


def test_checkpoints_of_different_configs_are_refused(tmp_path):
    a, _ = saved_checkpoint(tmp_path / "a.pt", "tiny", 0)
    b, _ = saved_checkpoint(tmp_path / "b.pt", "cpu-small", 1)
    with pytest.raises(CheckpointError, match="only checkpoints of one config can be averaged"):
        average_checkpoints([a, b])
    assert main(["weights", "average", a, b, "--out", str(tmp_path / "mean.pt")]) == 2
    assert not (tmp_path / "mean.pt").exists()


def test_one_checkpoint_or_a_source_as_output_is_refused(tmp_path, capsys):
    a, _ = saved_checkpoint(tmp_path / "a.pt", "tiny", 0)
    assert main(["weights", "average", a, "--out", str(tmp_path / "mean.pt")]) == 2
    assert "two or more" in capsys.readouterr().err
    b, _ = saved_checkpoint(tmp_path / "b.pt", "tiny", 1)
    before = (tmp_path / "a.pt").read_bytes()
    assert main(["weights", "average", a, b, "--out", a]) == 2
    assert "is one of the sources" in capsys.readouterr().err
    assert (tmp_path / "a.pt").read_bytes() == before
    assert not (tmp_path / "mean.pt").exists()


def test_zeroing_the_refinement_leaves_the_rest(tmp_path):
    a, sa = saved_checkpoint(tmp_path / "a.pt", "tiny", 0)
    assert sa["cont_refine.out.weight"].any()
    out = tmp_path / "auc_only.pt"
    assert main(["weights", "zero", a, "--layers", "cont_refine.out", "--out", str(out)]) == 0
    state = load_checkpoint(out, expected_config="tiny")["state_dict"]
    for key, value in state.items():
        if key.startswith("cont_refine.out."):
            assert not value.any()
        else:
            assert torch.equal(value, sa[key]), key


def test_zeroing_an_unknown_layer_names_it_and_writes_nothing(tmp_path, capsys):
    a, _ = saved_checkpoint(tmp_path / "a.pt", "tiny", 0)
    with pytest.raises(CheckpointError, match="no layer 'segnet.nope'"):
        zero_layers(a, ["cont_refine.out", "segnet.nope"])
    assert main(["weights", "zero", a, "--layers", "segnet.nope", "--out", str(tmp_path / "z.pt")]) == 2
    assert "segnet.nope" in capsys.readouterr().err
    assert not (tmp_path / "z.pt").exists()


def test_a_grown_copy_keeps_the_weights_and_adds_the_column_convs(tmp_path):
    """The grown payload is the checkpoint in the larger config: every weight it had,
    the added convs at zero, and a note of where it came from."""
    src, state = saved_checkpoint(tmp_path / "corr.pt", "cpu-small-corr", 0)
    payload = grown_payload(src, "cpu-small-corr-column")
    assert payload["config_name"] == "cpu-small-corr-column" and payload["train_meta"] == {"grown_from": src}
    grown = payload["state_dict"]
    for key, value in state.items():
        assert torch.equal(grown[key], value)
    added = sorted(set(grown) - set(state))
    assert added == ["segnet.column_first.weight", "segnet.column_last.weight"]
    assert all(not grown[k].any() for k in added)
    save_checkpoint(tmp_path / "grown.pt", payload)  # column correlations never turn into shifted ones
    with pytest.raises(CheckpointError, match="neither 'cpu-small-corr-shift' nor"):
        grown_payload(tmp_path / "grown.pt", "cpu-small-corr-shift")
