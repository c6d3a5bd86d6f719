"""Checkpoint round trip, wrong config, corrupt file, missing default weights, --init
across growth (the global-context block, growth blocks), the release copy."""

import dataclasses
import os
import random
import stat

import pytest
import torch

from bittc_core.checkpoint import (
    DEFAULT_WEIGHTS,
    REQUIRED_KEYS,
    CheckpointError,
    build_network,
    grows_into,
    init_network,
    load_checkpoint,
    make_payload,
    release_payload,
    save_checkpoint,
)
from bittc_core.model import BinaryTTCNet, get_config
from bittc_core.model.config import ModelConfig


def test_round_trip_rebuilds_the_same_network(tmp_path):
    torch.manual_seed(0)
    net = BinaryTTCNet(get_config("tiny")).eval()
    path = tmp_path / "m.pt"
    save_checkpoint(path, make_payload(net, "tiny", {"step": 3}))
    assert not list(tmp_path.glob("*.tmp"))  # the temp file was renamed
    ckpt = load_checkpoint(path, map_location="cpu", expected_config="tiny")
    assert ckpt["config"] == dataclasses.asdict(get_config("tiny")) and ckpt["train_meta"]["step"] == 3
    loaded = build_network(ckpt).eval()
    x = torch.rand(1, 3, 24, 48), torch.rand(1, 3, 24, 48), torch.tensor([[0.8, 0.95]])
    with torch.no_grad():
        torch.testing.assert_close(loaded(*x), net(*x))


def test_a_checkpoint_is_as_readable_as_any_new_file(tmp_path):
    old = os.umask(0o022)
    try:
        save_checkpoint(tmp_path / "m.pt", make_payload(BinaryTTCNet(get_config("tiny")), "tiny", {}))
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "m.pt").stat().st_mode) == 0o644


def test_wrong_config_is_a_clear_error(tmp_path):
    path = tmp_path / "m.pt"
    save_checkpoint(path, make_payload(BinaryTTCNet(get_config("tiny")), "tiny", {}))
    with pytest.raises(CheckpointError, match="'tiny', not 'cpu-small'"):
        load_checkpoint(path, expected_config="cpu-small")
    # a payload claiming a name whose sizes differ
    payload = make_payload(BinaryTTCNet(get_config("tiny")), "cpu-small", {})
    save_checkpoint(path, payload)
    with pytest.raises(CheckpointError, match="sizes differ"):
        load_checkpoint(path, expected_config="cpu-small")


def test_corrupt_or_foreign_file(tmp_path):
    path = tmp_path / "bad.pt"
    path.write_bytes(b"not a checkpoint at all")
    with pytest.raises(CheckpointError, match="corrupt"):
        load_checkpoint(path)
    torch.save({"weights": torch.zeros(2)}, path)
    with pytest.raises(CheckpointError, match="lacks the keys"):
        load_checkpoint(path)
    good = tmp_path / "good.pt"
    save_checkpoint(good, make_payload(BinaryTTCNet(get_config("tiny")), "tiny", {}))
    path.write_bytes(good.read_bytes()[:500])  # truncated
    with pytest.raises(CheckpointError, match="corrupt"):
        load_checkpoint(path)


def test_missing_default_weights_names_the_training_command(monkeypatch, tmp_path):
    if DEFAULT_WEIGHTS.exists():
        pytest.skip("default weights are shipped")
    with pytest.raises(CheckpointError, match="bittc train .*bittc_default.pt"):
        load_checkpoint(DEFAULT_WEIGHTS)


def _frames():
    g = torch.Generator().manual_seed(1)
    return torch.rand(1, 3, 96, 288, generator=g), torch.rand(1, 3, 96, 288, generator=g), torch.tensor([[0.8, 0.95]])


def _make_context_live(net):
    net.segnet.context.expand.bias.fill_(0.5)


def _make_decoder_block_live(net):
    net.segnet.dec_extra[-1][0].body[2].weight.fill_(0.5)  # the finest level's last norm


def _make_correlation_first_live(net):
    net.segnet.corr_first.weight.fill_(0.5)  # into SegNet's first conv


def _make_correlation_last_live(net):
    net.segnet.corr_last.weight.fill_(0.5)  # into the finest decoder conv


def _make_shift_first_live(net):
    net.segnet.shift_first.weight.fill_(0.5)


def _make_shift_last_live(net):
    net.segnet.shift_last.weight.fill_(0.5)


def _make_column_first_live(net):
    net.segnet.column_first.weight.fill_(0.5)


def _make_column_last_live(net):
    net.segnet.column_last.weight.fill_(0.5)


def _make_column_input_live(net):
    net.segnet.column_src_first.weight.fill_(0.5)  # the source warped by columns, into the first conv


@pytest.mark.parametrize(
    "source, grown, make_live",
    [
        ("cpu-small", "cpu-small-gc", _make_context_live),
        ("cpu-small", "cpu-medium", _make_decoder_block_live),
        ("cpu-small", "cpu-small-corr", _make_correlation_first_live),
        ("cpu-small", "cpu-small-corr", _make_correlation_last_live),
        ("cpu-small-corr", "cpu-small-corr-gc", _make_context_live),
        ("cpu-small-corr", "cpu-small-corr-shift", _make_shift_first_live),
        ("cpu-small-corr", "cpu-small-corr-shift", _make_shift_last_live),
        ("cpu-small-corr", "cpu-small-corr-column", _make_column_first_live),
        ("cpu-small-corr", "cpu-small-corr-column", _make_column_last_live),
        ("cpu-small-corr", "cpu-small-corr-column-input", _make_column_input_live),
        ("cpu-small-corr-column", "cpu-small-corr-column-input", _make_column_input_live),
    ],
)
def test_init_grows_as_the_identity(tmp_path, source, grown, make_live):
    torch.manual_seed(0)
    plain = BinaryTTCNet(get_config(source)).eval()
    if source.startswith("cpu-small-corr"):  # a trained volume: live, so the grown net must keep it
        with torch.no_grad():
            _make_correlation_first_live(plain)
            if get_config(source).corr_column:  # and its column correlations
                _make_column_first_live(plain)
                _make_column_last_live(plain)
    path = tmp_path / "plain.pt"
    save_checkpoint(path, make_payload(plain, source, {}))
    net = init_network(path, grown).eval()
    assert net.config == get_config(grown)
    with torch.no_grad():
        torch.testing.assert_close(net(*_frames()), plain(*_frames()), rtol=0, atol=0)
        # the added modules are live: once their last layer is non-zero the logits change
        make_live(net)
        assert not torch.allclose(net(*_frames()), plain(*_frames()))


def test_init_refuses_other_configs(tmp_path):
    path = tmp_path / "tiny.pt"
    save_checkpoint(path, make_payload(BinaryTTCNet(get_config("tiny")), "tiny", {}))
    with pytest.raises(CheckpointError, match="neither 'cpu-small-gc' nor a config 'cpu-small-gc' grows from"):
        init_network(path, "cpu-small-gc")
    # the block is only ever added, never dropped
    save_checkpoint(path, make_payload(BinaryTTCNet(get_config("cpu-small-gc")), "cpu-small-gc", {}))
    with pytest.raises(CheckpointError, match="neither 'cpu-small'"):
        init_network(path, "cpu-small")
    assert init_network(path, "cpu-small-gc").config == get_config("cpu-small-gc")
    # the sizes of cpu-small under another name: refused, as by load_checkpoint's expected_config
    save_checkpoint(path, make_payload(BinaryTTCNet(get_config("cpu-small")), "mine", {}))
    with pytest.raises(CheckpointError, match="'mine'"):
        init_network(path, "cpu-small")
    with pytest.raises(CheckpointError, match="'mine'"):
        init_network(path, "cpu-small-gc")


def test_init_never_shrinks(tmp_path):
    path = tmp_path / "medium.pt"
    save_checkpoint(path, make_payload(BinaryTTCNet(get_config("cpu-medium")), "cpu-medium", {}))
    for other in ("cpu-small", "cpu-small-gc"):  # back, and across
        with pytest.raises(CheckpointError, match=f"neither '{other}' nor a config '{other}' grows from"):
            init_network(path, other)


def test_grows_into_only_adds_identity_modules():
    tiny = get_config("tiny")
    assert grows_into(tiny, dataclasses.replace(tiny, refine_extra_blocks=2, global_context=True))
    assert not grows_into(tiny, tiny)  # nothing added
    assert not grows_into(dataclasses.replace(tiny, dec_extra_blocks=2), dataclasses.replace(tiny, dec_extra_blocks=1))
    # the correlation volume is switched on (0 -> n groups, any step), never resized
    corr = dataclasses.replace(tiny, corr_groups=2)
    assert grows_into(tiny, corr) and grows_into(tiny, dataclasses.replace(corr, corr_log_step=0.05))
    assert not grows_into(corr, dataclasses.replace(tiny, corr_groups=4))
    assert not grows_into(corr, dataclasses.replace(corr, corr_log_step=0.05))
    # the shifted correlations likewise: switched on, never changed
    shifted = dataclasses.replace(corr, corr_shift_px=2)
    assert grows_into(corr, shifted) and grows_into(tiny, shifted)
    assert not grows_into(shifted, dataclasses.replace(corr, corr_shift_px=3))
    assert not grows_into(shifted, corr)
    # the column correlations: switched on beside the volume, never off
    column = dataclasses.replace(corr, corr_column=True)
    assert grows_into(corr, column) and grows_into(tiny, column)
    assert grows_into(shifted, dataclasses.replace(shifted, corr_column=True))
    assert not grows_into(column, corr) and not grows_into(column, shifted) and not grows_into(shifted, column)
    # the second input (the source warped by columns): switched on, never off
    column_input = dataclasses.replace(column, column_input=True)
    assert grows_into(column, column_input) and grows_into(corr, column_input) and grows_into(tiny, column_input)
    assert not grows_into(column_input, column)
    assert not grows_into(tiny, dataclasses.replace(tiny, dec_extra_blocks=1, feat_channels=12))  # resized


def test_release_payload_drops_training_state(tmp_path):
    net = BinaryTTCNet(get_config("tiny"))
    path = tmp_path / "last.pt"
    save_checkpoint(path, make_payload(net, "tiny", {"step": 5}, train_state={"step": 5}))
    ckpt = load_checkpoint(path, expected_config="tiny")
    assert {"train_state", "model_config"} <= set(ckpt)
    release = release_payload(ckpt)
    assert sorted(release) == sorted(REQUIRED_KEYS)
    save_checkpoint(tmp_path / "ship.pt", release)
    assert "train_state" not in load_checkpoint(tmp_path / "ship.pt", expected_config="tiny")


def test_a_foreign_file_is_named_as_not_a_bittc_checkpoint_without_torch_advice(tmp_path):
    junk = tmp_path / "junk.pt"
    junk.write_bytes(random.Random(0).randbytes(4096))
    module = tmp_path / "module.pt"
    torch.save(torch.nn.Linear(2, 2), module)  # a valid torch file, not a weights-only payload
    tensors = tmp_path / "tensors.pt"
    torch.save({"weights": torch.zeros(2)}, tensors)  # a weights-only file without the bittc keys
    for path in (junk, module, tensors):
        with pytest.raises(CheckpointError) as e:
            load_checkpoint(path)
        msg = str(e.value)
        assert f"{str(path)!r} is not a bittc checkpoint" in msg, msg
        assert "weights_only" not in msg and "torch.load" not in msg and "safe_globals" not in msg, msg


def test_a_config_stored_before_the_column_correlations_loads_without_them():
    """A checkpoint written before ``corr_column`` and ``column_input`` existed stores
    neither key: it loads with both off, the config it was trained as; one written with
    the column correlations but before the column input loads without the input."""
    stored = dataclasses.asdict(get_config("cpu-small-corr"))
    del stored["corr_column"], stored["column_input"]
    assert ModelConfig.from_dict(stored) == get_config("cpu-small-corr")
    column = dataclasses.asdict(get_config("cpu-small-corr-column"))
    del column["column_input"]
    assert ModelConfig.from_dict(column) == get_config("cpu-small-corr-column")
