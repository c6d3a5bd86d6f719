"""Operations on checkpoints: a weight average, an ablation copy and a grown copy.

* :func:`average_checkpoints`: the element-wise mean of checkpoints of one config. Runs
  fine-tuned from the same weights stay in one basin of the loss, where the mean of
  their weights is often at least as good as either (weight averaging, "model soups").
  Floating-point tensors are averaged, batch-norm running statistics included; integer
  ones (``num_batches_tracked``) are taken from the first checkpoint.
* :func:`zero_layers`: a copy with residual branches' last layers zeroed. Some branches
  add a residual through a last layer that starts at zero, so zeroing it removes the
  branch and leaves everything else unchanged (``ABLATION_LAYERS``).
* :func:`grown_payload`: the weights of a checkpoint in a config that grows from its own
  (``bittc_core.checkpoint.init_network``: the added modules start as the identity), to
  train or time the larger config from exactly what the checkpoint computes.

All return a payload for :func:`bittc_core.checkpoint.save_checkpoint`; nothing is written.
"""

from __future__ import annotations

import dataclasses
import os

import torch

from bittc_core.checkpoint import CheckpointError, init_network, load_checkpoint, make_payload, release_payload

#: layer -> what zeroing it removes
ABLATION_LAYERS = {
    "cont_refine.out": "ContRefineNet's residual on log(eta_auc): the continuous output is the AUC alone (Eq. 12)",
    "segnet.context.expand": "the global-context block of cpu-small-gc",
    "segnet.corr_first": "with segnet.corr_last: the correlation volume of cpu-small-corr",
    "segnet.corr_last": "with segnet.corr_first: the correlation volume of cpu-small-corr",
}


def average_checkpoints(sources: list[str | os.PathLike]) -> dict:
    """The mean of ``sources`` (two or more checkpoints of one config) as a payload."""
    if len(sources) < 2:
        raise CheckpointError(f"averaging needs two or more checkpoints, got {len(sources)}")
    loaded = [load_checkpoint(src, map_location="cpu") for src in sources]
    # configs compared as loaded: a file saved before a config field existed stores none of
    # it and loads with its default (the shipped weights beside a fine-tune of them)
    configs = [ckpt["model_config"] for ckpt in loaded]
    ckpts = [release_payload(ckpt) for ckpt in loaded]
    first = ckpts[0]
    first["config"] = dataclasses.asdict(configs[0])
    for src, ckpt, config in zip(sources[1:], ckpts[1:], configs[1:]):
        if config != configs[0] or ckpt["state_dict"].keys() != first["state_dict"].keys():
            raise CheckpointError(
                f"checkpoint {str(src)!r} ({ckpt['config_name']!r}) does not match {str(sources[0])!r} "
                f"({first['config_name']!r}): only checkpoints of one config can be averaged"
            )
    for key, value in first["state_dict"].items():
        if value.is_floating_point():
            first["state_dict"][key] = torch.stack([c["state_dict"][key] for c in ckpts]).mean(dim=0)
    first["train_meta"] = {"average_of": [{"path": str(s), **c["train_meta"]} for s, c in zip(sources, ckpts)]}
    return first


def zero_layers(source: str | os.PathLike, layers: list[str]) -> dict:
    """A copy of ``source`` with the weight and bias of each of ``layers`` zeroed, as a payload.
    Every layer is checked before any is zeroed."""
    if not layers:
        raise CheckpointError("no layer to zero")
    ckpt = release_payload(load_checkpoint(source, map_location="cpu"))
    state = ckpt["state_dict"]
    for layer in layers:
        if f"{layer}.weight" not in state:
            raise CheckpointError(
                f"checkpoint {str(source)!r} ({ckpt['config_name']!r}) has no layer {layer!r} "
                f"(no {layer + '.weight'!r})"
            )
    for layer in layers:
        for key in (f"{layer}.weight", f"{layer}.bias"):  # a conv without bias has no .bias
            if key in state:
                state[key].zero_()
    ckpt["train_meta"] = {**ckpt.get("train_meta", {}), "zeroed_layers": list(layers)}
    return ckpt


def grown_payload(source: str | os.PathLike, config_name: str) -> dict:
    """``source``'s weights grown into config ``config_name`` (one that grows from the
    checkpoint's), as a payload whose ``train_meta`` names the source."""
    return make_payload(init_network(source, config_name), config_name, {"grown_from": str(source)})
