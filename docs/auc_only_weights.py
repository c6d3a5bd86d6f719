"""Write a copy of a checkpoint whose continuous refinement is the identity.

ContRefineNet adds a residual to log(eta_auc); zeroing its last conv makes that residual
zero, so the copy's continuous output is the AUC of the stacked maps alone (paper Eq. 12)
and everything else is unchanged. Evaluating both measures what the refinement adds:

    python docs/auc_only_weights.py bittc_core/weights/bittc_default.pt runs/auc_only.pt
    bittc eval --data data/bittc_v1 --method bittc --weights runs/auc_only.pt --split test
"""

import sys

from bittc_core.checkpoint import CheckpointError, load_checkpoint, save_checkpoint


def main(src: str, dst: str) -> None:
    ckpt = load_checkpoint(src, map_location="cpu")
    for key in ("train_state", "model_config"):  # derived on load; not part of a saved file
        ckpt.pop(key, None)
    for key in ("cont_refine.out.weight", "cont_refine.out.bias"):
        ckpt["state_dict"][key].zero_()
    save_checkpoint(dst, ckpt)
    print(f"wrote {dst}")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: python docs/auc_only_weights.py SRC.pt DST.pt")
    try:
        main(sys.argv[1], sys.argv[2])
    except CheckpointError as err:
        sys.exit(f"auc_only_weights: {err}")
