#!/usr/bin/env bash
# The shipped weights grown into cpu-small-corr-column (or COLUMN_CONFIG) and fine-tuned on scenes
# with pedestrians and cyclists, averaged with their start.
#
#   1. data: bittc_v9 (0.1 s pairs) or bittc_v11 (0.3 s pairs), the commands in
#      docs/train_vru_weights.sh and docs/train_pair3_weights.sh
#   2. this script: [START=FILE] [SHIP=1] [FRAME_STRIDE=N] [TRUNK_LR_MULT=M] [NEAR_OUTSIDE_WEIGHT=W] \
#        [COLUMN_CONFIG=NAME] bash docs/train_column_weights.sh [DATA] [OUT] [RELEASE]
#      bittc-2026.12-column:  bash docs/train_column_weights.sh data/bittc_v9 runs/column
#      bittc-2026.12-column3: FRAME_STRIDE=3 TRUNK_LR_MULT=0.2 NEAR_OUTSIDE_WEIGHT=4 \
#        bash docs/train_column_weights.sh data/bittc_v11 runs/column3 bittc-2026.12-column3
#      bittc-2026.12-column-input3: COLUMN_CONFIG=cpu-small-corr-column-input FRAME_STRIDE=3 \
#        TRUNK_LR_MULT=0.2 NEAR_OUTSIDE_WEIGHT=4 bash docs/train_column_weights.sh data/bittc_v11 \
#        runs/column-input3 bittc-2026.12-column-input3
#
# START (default: the shipped weights, cpu-small-corr) is grown into COLUMN_CONFIG (default
# cpu-small-corr-column): the correlation volume gains the column warps' correlations (rows
# scaled about the centre row, each column in place, where a road user on a collision course
# aligns; docs/vru.md), through two convs that start at zero, so the grown start computes what
# START did; cpu-small-corr-column-input also reads the source warped by columns as a second
# input, through a conv of its own that starts at zero. Then the recipe of
# docs/train_vru_weights.sh (the binary stage with the road users' pixels weighted 6x, the
# frozen continuous stage, the blend with the grown start), the new convs at 10x the learning
# rate as the volume's own (``segnet.column_``: with cpu-small-corr-column-input the second input's
# conv, ``segnet.column_src_first``, too). FRAME_STRIDE: the data's pairs span that many network
# intervals (3 for bittc_v11). TRUNK_LR_MULT: the feature extractor, SegNet and the refiner (all
# but those new convs) learn at that multiple of the rate. NEAR_OUTSIDE_WEIGHT: bittc train
# --near-outside-weight (the road just past a fence's static depth).
set -euo pipefail
CONFIG=${COLUMN_CONFIG:-cpu-small-corr-column}
NAME=${CONFIG#cpu-small-corr-}  # column or column-input: the defaults of OUT and RELEASE
DATA=${1:-data/bittc_v9}
OUT=${2:-runs/$NAME}
RELEASE=${3:-bittc-2026.12-$NAME}
BINARY_STEPS=${BINARY_STEPS:-2000}
CONT_STEPS=${CONT_STEPS:-250}
export FRAME_STRIDE=${FRAME_STRIDE:-1}
mkdir -p "$OUT"
python -c "import sys; from bittc_core.checkpoint import save_checkpoint; from bittc_core.checkpoint_ops import grown_payload
save_checkpoint(sys.argv[2], grown_payload(sys.argv[1], sys.argv[3]))" "${START:-bittc_core/weights/bittc_default.pt}" "$OUT/grown.pt" "$CONFIG"
START=$OUT/grown.pt
flags=(--vru-weight 6 --lr-mult segnet.column_=10)
if [ -n "${TRUNK_LR_MULT:-}" ]; then
    flags+=(--lr-mult "features.=$TRUNK_LR_MULT" --lr-mult "segnet.=$TRUNK_LR_MULT" --lr-mult "refine.=$TRUNK_LR_MULT")
fi
if [ -n "${NEAR_OUTSIDE_WEIGHT:-}" ]; then
    flags+=(--near-outside-weight "$NEAR_OUTSIDE_WEIGHT")
fi
source "$(dirname "$0")/release_steps.sh"
RECIPE_CONFIG=$CONFIG
finetune_release "$DATA" "$OUT" "$RELEASE" 90 "${flags[@]}"
