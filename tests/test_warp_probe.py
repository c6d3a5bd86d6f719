"""docs/warp_probe.py: the column warp scales rows as the shipped warp does and leaves columns in place."""

import importlib.util
import json
import sys
from pathlib import Path

import pytest
import torch

from bittc_core.model.warp import PaddedGrid, scale_warp

_SPEC = importlib.util.spec_from_file_location("warp_probe", Path(__file__).parents[1] / "docs" / "warp_probe.py")
probe = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(probe)

H, W = 9, 13
GRID = PaddedGrid.for_features(H, W, 1.5, 4)
ETA = torch.tensor([[1.0, 0.8, 0.6], [0.9, 0.7, 1.0]])  # (B, K)


def _sources(constant_along_x: bool) -> torch.Tensor:
    """(2, 2, H, W): two distinct sources, each varying along one axis only."""
    ramp = torch.linspace(-1.0, 2.0, H)[:, None].expand(H, W) if constant_along_x else torch.linspace(0.0, 3.0, W)
    ramp = ramp.expand(H, W)
    return torch.stack([torch.stack([ramp, 2 * ramp]), torch.stack([ramp + 1, -ramp])])


@pytest.mark.parametrize("unpadded", [False, True])
@pytest.mark.parametrize("per_hypothesis", [False, True])
def test_a_source_that_varies_only_along_rows_warps_as_the_centre_warp_does(unpadded, per_hypothesis):
    src = _sources(constant_along_x=True)
    if per_hypothesis:  # one source per hypothesis, batch-major, each distinct
        src = torch.cat([src[b : b + 1] * (1 + 0.1 * k) for b in range(2) for k in range(3)])
    ours, theirs = probe.column_warp(src, ETA, GRID, unpadded), scale_warp(src, ETA, GRID, unpadded)
    crop = (lambda x: x) if unpadded else GRID.crop
    assert ours.shape == theirs.shape
    assert torch.allclose(crop(ours), crop(theirs), atol=1e-6)


def test_every_column_stays_in_place_and_the_centre_warp_moves_them():
    src = _sources(constant_along_x=False)
    ours = GRID.crop(probe.column_warp(src, ETA, GRID))
    assert torch.allclose(ours, src.repeat_interleave(3, dim=0), atol=1e-6)
    theirs = scale_warp(src, ETA, GRID, unpadded=True)
    assert torch.allclose(theirs[0], src[0], atol=1e-6)  # eta = 1: both the identity
    assert not torch.allclose(theirs[1], src[0], atol=1e-3)


def test_the_probe_puts_its_warp_in_every_module_that_holds_the_shipped_one(monkeypatch, tmp_path):
    holders = [m for n, m in list(sys.modules.items()) if n.startswith("bittc_core") and hasattr(m, "scale_warp")]
    assert len(holders) >= 3  # warp, correlation, network
    for module in holders:
        monkeypatch.setattr(module, "scale_warp", scale_warp)
    out = tmp_path / "eval.json"
    seen = []

    def fake_eval(argv):
        seen.append(argv)
        out.write_text(json.dumps({"fence_lag_s": {}}))
        return 0

    monkeypatch.setattr(probe, "bittc", fake_eval)
    assert probe.main(["--warp", "column", "--", "--scenarios", "vru", "--method", "bittc", "--out", str(out)]) == 0
    assert seen == [["eval", "--scenarios", "vru", "--method", "bittc", "--out", str(out)]]
    assert all(module.scale_warp is probe.column_warp for module in holders)
    assert json.loads(out.read_text())["warp"] == "column"


@pytest.mark.parametrize(
    "args, named",
    [
        (["--method", "flow", "--out", "x.json"], "--method 'flow'"),
        (["--method", "bittc", "--backend=onnxruntime", "--out", "x.json"], "--backend 'onnxruntime'"),
        (["--out", "x.json"], "--method"),
        (["--method", "bittc"], "--out"),
    ],
)
def test_the_probe_refuses_what_would_not_read_its_warp_or_record_it(args, named, monkeypatch, tmp_path, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(probe, "bittc", lambda argv: pytest.fail("ran eval"))
    with pytest.raises(SystemExit) as exc:
        probe.main(["--warp", "column", "--", "--scenarios", "vru", *args])
    assert exc.value.code == 2
    assert named in capsys.readouterr().err
    assert not (tmp_path / "x.json").exists()
