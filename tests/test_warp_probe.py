"""docs/warp_probe.py: the column warp scales rows as the shipped warp does and leaves columns in place."""

import importlib.util
from pathlib import Path

import torch

from bittc_core.model.warp import PaddedGrid, scale_warp

_SPEC = importlib.util.spec_from_file_location("warp_probe", Path(__file__).parents[1] / "docs" / "warp_probe.py")
probe = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(probe)

H, W = 9, 13
GRID = PaddedGrid.for_features(H, W, 1.5, 4)
ETA = torch.tensor([[1.0, 0.8, 0.6]])


def test_a_source_that_varies_only_along_rows_warps_as_the_centre_warp_does():
    rows = torch.linspace(-1.0, 2.0, H)[:, None].expand(H, W)
    src = rows[None, None].repeat(1, 2, 1, 1)
    for unpadded in (False, True):
        ours = probe.column_warp(src, ETA, GRID, unpadded)
        theirs = scale_warp(src, ETA, GRID, unpadded)
        inside = GRID.crop(theirs) if not unpadded else theirs
        assert torch.allclose(GRID.crop(ours) if not unpadded else ours, inside, atol=1e-6)


def test_every_column_stays_in_place_and_the_centre_warp_moves_them():
    cols = torch.linspace(0.0, 3.0, W)[None, :].expand(H, W)
    src = cols[None, None]
    ours = probe.column_warp(src, ETA, GRID, unpadded=True)
    assert torch.allclose(ours, src.expand(3, 1, H, W), atol=1e-6)
    theirs = scale_warp(src, ETA, GRID, unpadded=True)
    assert torch.allclose(theirs[0], src[0], atol=1e-6)  # eta = 1: both the identity
    assert not torch.allclose(theirs[1:], src.expand(2, 1, H, W), atol=1e-3)


def test_the_probe_puts_its_warp_in_every_module_that_calls_it(monkeypatch):
    import bittc_core.model.correlation as correlation
    import bittc_core.model.network as network
    import bittc_core.model.warp as warp

    for module in (warp, correlation, network):
        monkeypatch.setattr(module, "scale_warp", module.scale_warp)
    monkeypatch.setattr(probe, "bittc", lambda argv: 0)
    assert probe.main(["--warp", "column", "--", "--scenarios", "vru"]) == 0
    assert warp.scale_warp is correlation.scale_warp is network.scale_warp is probe.column_warp
