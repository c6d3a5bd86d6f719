"""Training configuration (one frozen dataclass; the CLI fills it from its flags)."""

from __future__ import annotations

import math
from dataclasses import dataclass

STAGES = ("flow", "binary", "continuous")
DISTILL_SCOPES = ("all", "scenery", "scenery-vehicles")


@dataclass(frozen=True)
class TrainConfig:
    stage: str = "binary"  # one of STAGES
    steps: int = 2000  # optimiser steps of this stage
    batch_size: int = 8  # image pairs per step
    lr: float = 3e-4  # peak AdamW learning rate (field notes: 1e-3 flat collapsed)
    weight_decay: float = 1e-4
    warmup_steps: int = 200  # linear warm-up, then cosine decay to ``lr * final_lr_ratio``
    final_lr_ratio: float = 0.1
    clip_grad_norm: float = 1.0
    thresholds_per_pair: int = 4  # eta hypotheses per image pair (binary stage)
    shifts_per_pair: int = 2  # (u, v) shift hypotheses per image pair
    train_tau_min_s: float = 0.2  # [s] thresholds: eta uniform in [eta(tau_min), eta_max]
    train_eta_max: float = 1.1  # > 1: receding thresholds too (their negatives matter)
    # binary stage: this share of each pair's thresholds at the eta of a random valid pixel
    # (jittered; ``train.targets.sample_eta_at_pixels``), the rest uniform
    pixel_threshold_share: float = 0.0
    # binary stage: this share at the eta of a random in-path vehicle pixel (the vehicle a
    # braking controller reads; tighter jitter, ``train.targets.INPATH_THRESHOLD_JITTER``),
    # uniform for a pair without one
    inpath_threshold_share: float = 0.0
    actor_weight: float = 1.0  # binary TTC loss weight of vehicle pixels, moving or not (instance > 0); scenery 1
    # binary TTC loss weight of in-path vehicle pixels (``data.dataset.INPATH_HALF_WIDTH_M``),
    # instead of actor_weight there: what a braking controller reads
    inpath_weight: float = 1.0
    # binary TTC loss weight of pedestrian and cyclist pixels (``data.dataset.class_map``),
    # instead of the two above there: small targets the braking of road users reads
    vru_weight: float = 1.0
    # binary TTC loss weight of scenery pixels outside a threshold's fence whose TTC is at most
    # twice the threshold, instead of 1 (per threshold; the distillation term alike): the road
    # just past a fence's static depth, which a network read on wide pairs fences
    # (``train.targets.near_outside``)
    near_outside_weight: float = 1.0
    lovasz_weight: float = 0.0  # binary stage: + this x Lovasz two-class IoU surrogate per map
    # binary stage: + this x BCE towards a frozen teacher's flip-averaged maps (``train.distill``;
    # pixels weighted as in the ground-truth BCE); > 0 needs a teacher network of the same config
    distill_weight: float = 0.0
    # where the teacher teaches (one of DISTILL_SCOPES): "all" adds its term beside the ground
    # truth on every pixel; "scenery" replaces the ground truth by the teacher's maps on scenery
    # pixels (instance 0), their BCE weight times ``distill_weight`` (relative to the ground
    # truth's pixels; the Lovasz term reads the teacher's maps rounded), and leaves the actors' ground
    # truth alone: the scenery's fences (the road's own fence edge that a controller's margins
    # were tuned on) stay the teacher's while the actors learn from new data; "scenery-vehicles"
    # replaces it on vehicles too, so that only pedestrians and cyclists learn from the data
    distill_scope: str = "all"
    ttc_weight: float = 0.8  # paper: binary TTC 0.8, binary flow 0.2
    flow_weight: float = 0.2
    cont_bce_weight: float = 0.1  # paper: BCE on the stacked maps 0.1, SmoothL1 on AUC 0.9
    cont_sl1_weight: float = 0.9
    # continuous stage: train ContRefineNet only; the binary network (extractor, SegNet,
    # SegRefineNet) is frozen with its batch-norm statistics, so the geofences keep the
    # binary stage's accuracy (a small model fine-tuned end to end trades them for MiD)
    freeze_binary: bool = False
    # keep every batch norm's running statistics as the start had them (their scale and shift
    # still learn): a fine-tune on pairs of another interval (``frame_stride``) or scenes of
    # another mix would otherwise move the statistics the whole network normalises by
    freeze_norm_stats: bool = False
    # (parameter-name prefix, multiplier) pairs: those parameters learn at lr x multiplier
    # (``train.params.param_groups``), e.g. modules added by growth, which start at zero and
    # would otherwise stay small beside weights trained for thousands of steps
    lr_mults: tuple[tuple[str, float], ...] = ()
    val_every: int = 250  # steps between validations (and checkpoints)
    # also keep the weights of every validation step (``RunPaths.snapshot``), e.g. to
    # average the tail of a run (``bittc weights average``)
    keep_checkpoints: bool = False
    val_limit: int = 64  # validation pairs
    log_every: int = 10  # steps between CSV rows
    num_workers: int = 0  # DataLoader workers
    seed: int = 0

    def __post_init__(self) -> None:
        if self.stage not in STAGES:
            raise ValueError(f"stage {self.stage!r}: expected one of {STAGES}")
        for name in (
            "steps",
            "batch_size",
            "thresholds_per_pair",
            "shifts_per_pair",
            "val_every",
            "val_limit",
            "log_every",
        ):
            if getattr(self, name) <= 0:
                raise ValueError(f"{name}={getattr(self, name)}: must be > 0")
        if self.freeze_binary and self.stage != "continuous":
            raise ValueError(f"freeze_binary applies to the continuous stage, not {self.stage!r}")
        if self.actor_weight <= 0:
            raise ValueError(f"actor_weight={self.actor_weight}: must be > 0")
        if self.inpath_weight <= 0:
            raise ValueError(f"inpath_weight={self.inpath_weight}: must be > 0")
        if self.vru_weight <= 0:
            raise ValueError(f"vru_weight={self.vru_weight}: must be > 0")
        if self.near_outside_weight <= 0:
            raise ValueError(f"near_outside_weight={self.near_outside_weight}: must be > 0")
        if self.lovasz_weight < 0:
            raise ValueError(f"lovasz_weight={self.lovasz_weight}: must be >= 0")
        if self.distill_weight < 0:
            raise ValueError(f"distill_weight={self.distill_weight}: must be >= 0")
        if self.distill_scope not in DISTILL_SCOPES:
            raise ValueError(f"distill_scope {self.distill_scope!r}: expected one of {DISTILL_SCOPES}")
        if self.distill_scope != "all" and self.distill_weight == 0:
            raise ValueError(f"distill_scope {self.distill_scope!r} needs a teacher: distill_weight > 0")
        if self.distill_weight > 0 and self.stage != "binary":
            raise ValueError(f"distill_weight applies to the binary stage, not {self.stage!r}")
        if not 0.0 <= self.pixel_threshold_share <= 1.0:
            raise ValueError(f"pixel_threshold_share={self.pixel_threshold_share}: must be in [0, 1]")
        if not 0.0 <= self.inpath_threshold_share <= 1.0 - self.pixel_threshold_share:
            raise ValueError(
                f"inpath_threshold_share={self.inpath_threshold_share}: must be in [0, 1 - pixel_threshold_share "
                f"= {1.0 - self.pixel_threshold_share:g}]"
            )
        if self.warmup_steps < 0:
            raise ValueError(f"warmup_steps={self.warmup_steps}: must be >= 0")
        for prefix, mult in self.lr_mults:
            if not prefix or not 0 < mult < math.inf:
                raise ValueError(f"lr_mults ({prefix!r}, {mult}): needs a prefix and a multiplier > 0, finite")
        if len({prefix for prefix, _ in self.lr_mults}) != len(self.lr_mults):
            raise ValueError(f"lr_mults {self.lr_mults}: a prefix is named twice")
        if self.lr <= 0 or self.clip_grad_norm <= 0:
            raise ValueError("lr and clip_grad_norm must be > 0")
