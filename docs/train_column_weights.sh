#!/usr/bin/env bash
# The shipped weights grown into cpu-small-corr-column and fine-tuned on scenes with pedestrians
# and cyclists, averaged with their start.
#
#   1. data: bittc_v9, the command in docs/train_vru_weights.sh
#   2. this script: [START=FILE] [SHIP=1] bash docs/train_column_weights.sh [DATA_V9] [OUT] [RELEASE]
#
# START (default: the shipped weights, cpu-small-corr) is grown into cpu-small-corr-column: the
# correlation volume gains the column warps' correlations (rows scaled about the centre row,
# each column in place, where a road user on a collision course aligns; docs/vru.md), through
# two convs that start at zero, so the grown start computes what START did. Then the recipe of
# docs/train_vru_weights.sh (the binary stage with the road users' pixels weighted 6x, the
# frozen continuous stage, the blend with the grown start), the new convs at 10x the learning
# rate as the volume's own.
set -euo pipefail
DATA9=${1:-data/bittc_v9}
OUT=${2:-runs/column}
RELEASE=${3:-bittc-2026.12-column}
BINARY_STEPS=${BINARY_STEPS:-2000}
CONT_STEPS=${CONT_STEPS:-250}
export CONFIG=cpu-small-corr-column
mkdir -p "$OUT"
python -c "import sys; from bittc_core.checkpoint import init_network, make_payload, save_checkpoint
save_checkpoint(sys.argv[2], make_payload(init_network(sys.argv[1], sys.argv[3]), sys.argv[3], {'grown_from': sys.argv[1]}))" \
    "${START:-bittc_core/weights/bittc_default.pt}" "$OUT/grown.pt" "$CONFIG"
START=$OUT/grown.pt
source "$(dirname "$0")/release_steps.sh"
finetune_release "$DATA9" "$OUT" "$RELEASE" 90 --vru-weight 6 --lr-mult segnet.column_=10
