"""Write a copy of a checkpoint with residual branches' last layers zeroed (an ablation).

Some branches of the network add a residual through a last layer that starts at zero, so
zeroing it removes the branch and leaves everything else unchanged:

* ``cont_refine.out``: ContRefineNet's residual on log(eta_auc); the copy's continuous
  output is the AUC of the stacked maps alone (paper Eq. 12);
* ``segnet.context.expand``: the global-context block of ``cpu-small-gc``;
* ``segnet.corr_first segnet.corr_last`` (both): the correlation volume of
  ``cpu-small-corr``; the copy computes what ``cpu-small`` with the same weights would.

Evaluating the copy beside the original measures what the branch adds:

    python docs/zero_layer.py bittc_core/weights/bittc_default.pt runs/auc_only.pt cont_refine.out
    bittc eval --data data/bittc_v1 --method bittc --weights runs/auc_only.pt --split test
"""

import sys

from bittc_core.checkpoint import CheckpointError, load_checkpoint, release_payload, save_checkpoint


def main(src: str, dst: str, *layers: str) -> None:
    ckpt = release_payload(load_checkpoint(src, map_location="cpu"))
    state = ckpt["state_dict"]
    for layer in layers:  # all checked before anything is written
        if f"{layer}.weight" not in state:
            raise CheckpointError(f"checkpoint {src!r} ({ckpt['config_name']!r}) has no layer {layer!r} "
                                  f"(no {layer + '.weight'!r})")
    for layer in layers:
        for key in (f"{layer}.weight", f"{layer}.bias"):  # a conv without bias has no .bias
            if key in state:
                state[key].zero_()
    save_checkpoint(dst, ckpt)
    print(f"wrote {dst} ({', '.join(layers)} zeroed)")


if __name__ == "__main__":
    if len(sys.argv) < 4:
        sys.exit("usage: python docs/zero_layer.py SRC.pt DST.pt LAYER [LAYER ...]   (LAYER: cont_refine.out, "
                 "segnet.context.expand, segnet.corr_first segnet.corr_last)")
    try:
        main(*sys.argv[1:])
    except CheckpointError as err:
        sys.exit(f"zero_layer: {err}")
