#!/usr/bin/env bash
# A fine-tune of the shipped weights on images through the camera sensor model with the video
# codec, and vehicles plain, detailed or dressed (docs/sensor.md), averaged with its start.
#
#   1. data: for s in "val 400" "train 8000"; do set -- $s; bittc generate --out data/bittc_v10 \
#              --fovea-share 0.5 --vehicle-texture assorted --realism-share 0.5 --realism-codecs jpeg+video \
#              --split $1 --samples $2 --seed 10 --workers 2; done
#   2. this script: [START=FILE] [SHIP=1] bash docs/train_realism2_weights.sh [DATA_V10] [OUT] [RELEASE]
#
# START is the shipped bittc-2026.12-realism1-blend (bittc_core/weights/bittc_default.pt) by
# default. bittc_v10 is bittc_v7's recipe (half the samples through a fovea, half of the clips
# through a sensor) with the video codec beside JPEG and a third of the vehicles dressed
# (framed windows, plates, lamps). The steps are those of docs/train_realism_weights.sh
# (docs/release_steps.sh: finetune_release).
set -euo pipefail
DATA10=${1:-data/bittc_v10}
OUT=${2:-runs/realism2}
RELEASE=${3:-bittc-2026.12-realism2}
BINARY_STEPS=${BINARY_STEPS:-1500}
CONT_STEPS=${CONT_STEPS:-250}
START=${START:-bittc_core/weights/bittc_default.pt}
mkdir -p "$OUT"
source "$(dirname "$0")/release_steps.sh"
finetune_release "$DATA10" "$OUT" "$RELEASE" 100
