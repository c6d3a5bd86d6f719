"""What a stage trains: frozen modules and AdamW parameter groups with learning-rate multiples."""

from __future__ import annotations

import torch

from bittc_core.train.config import TrainConfig

#: what ``freeze_binary`` freezes (their batch-norm statistics too): the binary network
BINARY_MODULES = ("features", "segnet", "refine")


def frozen_prefixes(cfg: TrainConfig) -> tuple[str, ...]:
    """Parameter-name prefixes that a stage of ``cfg`` does not train."""
    return tuple(f"{m}." for m in BINARY_MODULES) if cfg.freeze_binary else ()


def param_groups(
    net: torch.nn.Module, lr_mults: tuple[tuple[str, float], ...], frozen: tuple[str, ...] = ()
) -> list[dict]:
    """The trainable parameters (``requires_grad``, not under a ``frozen`` prefix) as AdamW
    groups, each with its ``lr_mult``: a parameter whose name starts with a prefix of
    ``lr_mults`` learns at that multiple of the scheduled rate (the longest matching
    prefix wins), every other one at 1x. A prefix that names no trainable parameter is an
    error (a typo would silently do nothing)."""
    groups: dict[float, list[torch.nn.Parameter]] = {}
    used = set()
    for name, q in net.named_parameters():
        if not q.requires_grad or name.startswith(frozen):
            continue
        match = max((p for p, _ in lr_mults if name.startswith(p)), key=len, default=None)
        used.add(match)
        groups.setdefault(dict(lr_mults)[match] if match else 1.0, []).append(q)
    unused = [p for p, _ in lr_mults if p not in used]
    if unused:
        raise ValueError(f"lr_mults: no trainable parameter name starts with {unused}")
    return [{"params": params, "lr_mult": mult} for mult, params in groups.items()]
