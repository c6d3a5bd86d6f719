"""Model configs: one frozen dataclass, a registry of named sizes.

A checkpoint stores ``asdict(config)`` and its name, so a network is rebuilt from the
checkpoint alone (``ModelConfig.from_dict``), with no flags.

Conventions shared by every config (see ``bittc_core.model.network``):
    * input frames are 3-channel images in [0, 1] whose height and width are
      multiples of 3 px (the features live at 1/3 resolution);
    * ``frame_dt_s`` is the frame interval the network was trained for: a threshold
      tau_i [s] becomes eta_i = tau_i / (tau_i + frame_dt_s);
    * geofence thresholds outside [tau_min_s, tau_max_s] are rejected by the estimator;
    * continuous mode stacks ``cont_levels`` maps at eta thresholds spaced uniformly
      over [cont_eta_min, cont_eta_max] (bin centres, see ``model.auc``).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

NORMS = ("none", "batch", "group")
#: Growth fields: raising one adds modules that start as the identity (``GrowthBlock``,
#: ``GlobalContext``), so a trained network of the smaller config carries over to the
#: larger one unchanged (``checkpoint.init_network``) and training goes on from there.
#: Unchanged in eval mode, exactly; in train mode the finest decoder level's batch norm
#: takes its statistics over a crop widened by 2 px a side per decoder growth block.
GROWTH_COUNTS = ("feat_extra_blocks", "dec_extra_blocks", "refine_extra_blocks")
GROWTH_FLAGS = ("global_context", "corr_column", "column_input")
#: Growth switches: counts that may only be switched on (0 -> n) by growth: the
#: correlation volume's convs start at zero, but its width depends on the count, so
#: n -> m != n does not carry over; the shifted correlations' width does not depend on
#: their range, but trained convs would read another range's channels as theirs. With
#: the volume off, ``corr_log_step`` is free.
GROWTH_SWITCHES = ("corr_groups", "corr_shift_px")


@dataclass(frozen=True)
class ModelConfig:
    # FeatExtractNet (PSMNet-style, output at 1/3 resolution)
    stem_channels: int = 32  # channels of the stride-3 stem
    feat_channels: int = 32  # channels of the output feature map
    feat_res_blocks: int = 4  # residual blocks at 1/3 resolution
    spp_pool_sizes: tuple[int, ...] = (16, 8, 4, 2)  # average-pool windows [feature px]
    spp_channels: int = 16  # channels of each pyramid branch
    feat_extra_blocks: int = 0  # identity-at-init residual blocks after those (growth, below)
    # SegNet2D (encoder-decoder with skip connections)
    enc_channels: tuple[int, ...] = (128, 256, 512, 1024, 1024)
    dec_channels: tuple[int, ...] = (1024, 512, 256, 128, 64)  # coarse to fine
    full_res_skip: bool = True  # last decoder block also sees the input volume
    pad_factor: float = 1.5  # features are zero-padded to this multiple of their size
    global_context: bool = False  # pooled bottleneck summary added back (not in the paper)
    dec_extra_blocks: int = 0  # identity-at-init residual blocks per decoder level (growth)
    # group-wise correlation of f_ref with the source warped at eta_i and eta_i * exp(+-step)
    # (not in the paper, ``model.correlation``): 0 = off; its convs start at zero (growth)
    corr_groups: int = 0  # channel groups (divides feat_channels)
    corr_log_step: float = 0.03  # [log eta] offset of the two outer warps
    # the volume's shifted correlations (``model.correlation.shifted_correlation``): the
    # largest over sideways shifts up to this many feature px; 0 = off; convs start at zero
    corr_shift_px: int = 0
    # the volume's column correlations (``model.correlation``): the three warps again with
    # each column left in place (rows scaled only), where a road user on a collision course
    # aligns; convs start at zero
    corr_column: bool = False
    # the source features warped by columns (``model.warp.column_warp``) as a second input
    # beside the centre-warped one, through their own conv into SegNet's first encoder conv
    # (and finest decoder conv with ``full_res_skip``); those start at zero
    column_input: bool = False
    # SegRefineNet (guided by the reference image)
    guide_channels: int = 16
    refine_channels: int = 8
    refine_layers: int = 4
    refine_extra_blocks: int = 0  # identity-at-init residual blocks before the last conv (growth)
    # ContRefineNet (StereoNet-style refinement of the AUC output)
    cont_channels: int = 32
    cont_dilations: tuple[int, ...] = (1, 2, 4, 8, 1, 1)
    cont_refine_levels: bool = False  # also feed it the stacked maps (not in the paper)
    # normalisation layers: "none" (the paper), "batch" or "group"
    norm: str = "none"
    # trained ranges
    frame_dt_s: float = 0.1  # [s] frame interval the network was trained at
    tau_min_s: float = 0.2  # [s] smallest geofence threshold accepted
    tau_max_s: float = 10.0  # [s] largest geofence threshold accepted
    max_shift_px: float = 30.0  # [px of the input] largest binary-flow shift trained
    cont_eta_min: float = 0.6  # lowest eta of the continuous volume
    cont_eta_max: float = 1.2  # highest eta of the continuous volume
    cont_levels: int = 24  # number of maps stacked in continuous mode

    def __post_init__(self) -> None:
        if self.norm not in NORMS:
            raise ValueError(f"ModelConfig.norm={self.norm!r}: expected one of {NORMS}")
        if len(self.enc_channels) != len(self.dec_channels) or not self.enc_channels:
            raise ValueError(
                f"ModelConfig: enc_channels {self.enc_channels} and dec_channels "
                f"{self.dec_channels} must be non-empty and of equal length"
            )
        if not 0.0 < self.tau_min_s < self.tau_max_s:
            raise ValueError(f"ModelConfig: bad tau range [{self.tau_min_s}, {self.tau_max_s}] s")
        if not 0.0 < self.cont_eta_min < self.cont_eta_max or self.cont_levels < 2:
            raise ValueError(
                f"ModelConfig: bad continuous volume eta [{self.cont_eta_min}, "
                f"{self.cont_eta_max}] x {self.cont_levels} levels"
            )
        for name in (*GROWTH_COUNTS, *GROWTH_SWITCHES):
            if getattr(self, name) < 0:
                raise ValueError(f"ModelConfig.{name}={getattr(self, name)}: must be >= 0")
        if self.corr_groups and self.feat_channels % self.corr_groups:
            raise ValueError(
                f"ModelConfig.corr_groups={self.corr_groups}: must divide feat_channels={self.feat_channels}"
            )
        if self.corr_shift_px and not self.corr_groups:
            raise ValueError(
                f"ModelConfig.corr_shift_px={self.corr_shift_px}: needs the correlation volume (corr_groups > 0)"
            )
        if self.corr_column and not self.corr_groups:
            raise ValueError("ModelConfig.corr_column=True: needs the correlation volume (corr_groups > 0)")
        if not 0.0 < self.corr_log_step < math.inf:
            raise ValueError(f"ModelConfig.corr_log_step={self.corr_log_step}: must be > 0")
        if self.pad_factor < 1.0:
            raise ValueError(f"ModelConfig.pad_factor={self.pad_factor}: must be >= 1")

    @property
    def down_factor(self) -> int:
        """The padded feature map must be divisible by this (one /2 per encoder block)."""
        return 2 ** len(self.enc_channels)

    @classmethod
    def from_dict(cls, values: dict) -> ModelConfig:
        """Rebuild from ``asdict(config)``; unknown keys are an error, lists -> tuples."""
        names = {f.name: f for f in dataclasses.fields(cls)}
        unknown = sorted(set(values) - set(names))
        if unknown:
            raise ValueError(f"ModelConfig: unknown keys {unknown}")
        fixed = {k: tuple(v) if isinstance(v, list) else v for k, v in values.items()}
        return cls(**fixed)


#: name -> config. ``paper``: the paper's sizes, no normalisation (~91 M params).
#: ``cpu-small``: the CPU default (slim extractor, narrow 4-level SegNet, batch norm,
#: one hidden refine layer), tuned with ``bittc bench`` on 2 cores at 96x288: ~10 ms for
#: one threshold in streaming mode, ~3 ms per extra threshold.
#: ``cpu-small-gc``: ``cpu-small`` plus the global-context block at the SegNet bottleneck
#: (an experiment: the static ground's tau = Z / v_ego hangs on one speed for the whole
#: image; see the README for what it measured).
#: ``cpu-medium``: ``cpu-small`` grown by identity-at-init residual blocks (three in the
#: feature extractor, which runs once per frame, one per SegNet decoder level), trained
#: from a ``cpu-small`` checkpoint (``bittc train --config cpu-medium --init``). An
#: experiment (README): no gain in one run, and ~22 ms for one threshold, over budget.
#: ``cpu-small-corr``: ``cpu-small`` plus the group-wise correlation volume (8 groups of 2
#: channels, three warps per threshold) fed to SegNet's first and last convs, both
#: starting at zero, trained from a ``cpu-small`` checkpoint (README: what it measured).
#: ``cpu-small-corr-gc``: ``cpu-small-corr`` plus the global-context block (an
#: experiment: trained from a ``cpu-small-corr`` checkpoint with both added parts at a
#: raised learning rate, ``--lr-mult``; README: one run, the block stayed unused).
#: ``cpu-small-corr-shift``: ``cpu-small-corr`` plus the volume's shifted correlations
#: (up to 2 feature px, 6 px of the input, either way along the rows), fed to SegNet's
#: first and last convs by two more convs that start at zero, trained from a
#: ``cpu-small-corr`` checkpoint: a road user crossing between the pair's frames.
#: ``cpu-small-corr-column``: ``cpu-small-corr`` plus the volume's column correlations
#: (the three warps with each column in place, rows scaled about the centre row), fed to
#: SegNet's first and last convs by two more convs that start at zero, trained from a
#: ``cpu-small-corr`` checkpoint: a road user on a collision course keeps its bearing, so
#: it grows about its own column, where the scale warp about the centre misses it.
#: ``cpu-small-corr-column-input``: ``cpu-small-corr-column`` plus the source features
#: warped by columns as a second input of SegNet's first encoder conv, through a conv of
#: their own that starts at zero, trained from a ``cpu-small-corr`` or
#: ``cpu-small-corr-column`` checkpoint: SegNet reads both alignments, not only their
#: correlations.
#: ``tiny``: unit tests only.
_CPU_SMALL = ModelConfig(
    stem_channels=16,
    feat_channels=16,
    feat_res_blocks=2,
    spp_pool_sizes=(8, 4, 2),
    spp_channels=8,
    enc_channels=(16, 32, 48, 64),
    dec_channels=(48, 32, 16, 16),
    full_res_skip=False,
    guide_channels=8,
    refine_channels=8,
    refine_layers=1,
    cont_channels=16,
    cont_dilations=(1, 2, 4, 1),
    cont_refine_levels=True,
    norm="batch",
)
CONFIGS: dict[str, ModelConfig] = {
    "paper": ModelConfig(),
    "cpu-small": _CPU_SMALL,
    "cpu-small-gc": dataclasses.replace(_CPU_SMALL, global_context=True),
    "cpu-medium": dataclasses.replace(_CPU_SMALL, feat_extra_blocks=3, dec_extra_blocks=1),
    "cpu-small-corr": dataclasses.replace(_CPU_SMALL, corr_groups=8),
    "cpu-small-corr-gc": dataclasses.replace(_CPU_SMALL, corr_groups=8, global_context=True),
    "cpu-small-corr-shift": dataclasses.replace(_CPU_SMALL, corr_groups=8, corr_shift_px=2),
    "cpu-small-corr-column": dataclasses.replace(_CPU_SMALL, corr_groups=8, corr_column=True),
    "cpu-small-corr-column-input": dataclasses.replace(_CPU_SMALL, corr_groups=8, corr_column=True, column_input=True),
    "tiny": ModelConfig(
        stem_channels=8,
        feat_channels=8,
        feat_res_blocks=1,
        spp_pool_sizes=(4, 2),
        spp_channels=4,
        enc_channels=(8, 12),
        dec_channels=(12, 8),
        full_res_skip=True,
        guide_channels=4,
        refine_channels=4,
        refine_layers=2,
        cont_channels=8,
        cont_dilations=(1, 2),
        norm="batch",
        cont_levels=8,
    ),
}


def get_config(name: str) -> ModelConfig:
    try:
        return CONFIGS[name]
    except KeyError:
        raise ValueError(f"unknown model config {name!r}; known: {sorted(CONFIGS)}") from None
