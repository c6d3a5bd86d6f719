"""Write the element-wise mean of two or more checkpoints of one config (a weight average).

Runs fine-tuned from the same weights stay in one basin of the loss, where the mean
of their weights is often at least as good as either (weight averaging, "model
soups"). Floating-point tensors are averaged, batch-norm running statistics included;
integer ones (``num_batches_tracked``) are taken from the first checkpoint:

    python docs/average_weights.py runs/avg.pt runs/default/continuous.pt runs/default/continuous_distill.pt
    bittc eval --data data/bittc_v2 --method bittc --weights runs/avg.pt --split val
"""

import sys

import torch

from bittc_core.checkpoint import CheckpointError, load_checkpoint, release_payload, save_checkpoint


def main(dst: str, *sources: str) -> None:
    ckpts = [release_payload(load_checkpoint(src, map_location="cpu")) for src in sources]
    first = ckpts[0]
    for src, ckpt in zip(sources[1:], ckpts[1:]):
        if ckpt["config"] != first["config"] or ckpt["state_dict"].keys() != first["state_dict"].keys():
            raise CheckpointError(f"checkpoint {src!r} ({ckpt['config_name']!r}) does not match {sources[0]!r} "
                                  f"({first['config_name']!r}): only checkpoints of one config can be averaged")
    for key, value in first["state_dict"].items():
        if value.is_floating_point():
            first["state_dict"][key] = torch.stack([c["state_dict"][key] for c in ckpts]).mean(dim=0)
    first["train_meta"] = {"average_of": [{"path": src, **ckpt["train_meta"]} for src, ckpt in zip(sources, ckpts)]}
    save_checkpoint(dst, first)
    print(f"wrote {dst} (mean of {len(sources)} checkpoints)")


if __name__ == "__main__":
    if len(sys.argv) < 4:
        sys.exit("usage: python docs/average_weights.py DST.pt SRC1.pt SRC2.pt [SRC3.pt ...]")
    try:
        main(*sys.argv[1:])
    except CheckpointError as err:
        sys.exit(f"average_weights: {err}")
