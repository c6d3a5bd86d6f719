"""`bittc weights average|zero`: a weight average of checkpoints, or an ablation copy."""

from __future__ import annotations

import argparse

from bittc_core.errors import CliError


def add_parser(sub) -> argparse.ArgumentParser:
    p = sub.add_parser("weights", help="average checkpoints of one config, or zero a branch for an ablation")
    wsub = p.add_subparsers(dest="weights_command", metavar="ACTION", required=True)
    a = wsub.add_parser(
        "average",
        help="the element-wise mean of two or more checkpoints of one config",
        description="Writes the mean of the checkpoints' floating-point tensors (batch-norm statistics "
        "included; counters from the first). Evaluate it with bittc eval --weights OUT.",
    )
    a.add_argument("sources", nargs="+", metavar="SRC", help="checkpoints of one config (two or more)")
    a.add_argument("--out", required=True, metavar="FILE", help="the checkpoint to write (not one of the sources)")
    z = wsub.add_parser(
        "zero",
        help="a copy of a checkpoint with residual branches' last layers zeroed (an ablation)",
        description="Zeroes the weight and bias of each layer; for a branch whose last layer starts at "
        "zero this removes the branch and leaves everything else unchanged. Layers: "
        "cont_refine.out (the continuous output becomes the AUC alone), segnet.context.expand "
        "(global context), segnet.corr_first and segnet.corr_last together (correlation volume).",
    )
    z.add_argument("source", metavar="SRC", help="the checkpoint to copy")
    z.add_argument("--layers", nargs="+", required=True, metavar="LAYER", help="layer names, e.g. cont_refine.out")
    z.add_argument("--out", required=True, metavar="FILE", help="the checkpoint to write (not the source)")
    return p


def run(args) -> int:
    from pathlib import Path

    from bittc_core.checkpoint import save_checkpoint
    from bittc_core.checkpoint_ops import average_checkpoints, zero_layers

    sources = args.sources if args.weights_command == "average" else [args.source]
    out = Path(args.out)
    if any(Path(s).resolve() == out.resolve() for s in sources):
        raise CliError(f"--out {args.out}: is one of the sources; write the result to a new file")
    if args.weights_command == "average":
        payload, what = average_checkpoints(sources), f"mean of {len(sources)} checkpoints"
    else:
        payload, what = zero_layers(args.source, args.layers), f"{', '.join(args.layers)} zeroed"
    save_checkpoint(out, payload)
    print(f"wrote {out} ({what})")
    return 0
