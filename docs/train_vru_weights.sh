#!/usr/bin/env bash
# A fine-tune of the shipped weights on scenes with pedestrians and cyclists, averaged with its start.
#
#   1. data: for s in "val 400" "test 400" "train 8000"; do set -- $s; bittc generate --out data/bittc_v9 \
#              --fovea-share 0.4 --vehicle-texture mixed --realism-share 0.5 --realism-codecs jpeg --vru-share 0.6 --split $1 \
#              --samples $2 --seed 9 --workers 2; done
#   2. this script: [START=FILE] [SHIP=1] bash docs/train_vru_weights.sh [DATA_V9] [OUT] [RELEASE]
#
# START is the shipped bittc-2026.12-realism1-blend (bittc_core/weights/bittc_default.pt) by
# default. bittc_v9 is bittc_v7's recipe (samples through a fovea, half through a sensor,
# vehicles plain or textured) with pedestrians and cyclists in 60 % of its scenes
# (sim.random_vrus). One binary run with the in-path actor pixels and the pedestrian and
# cyclist pixels weighted (the checkpoint kept is the best by validation mIoU), then the frozen continuous stage; its best
# checkpoint is written to OUT/release.pt with its release name. Last, the blend: the
# element-wise mean of START and OUT/release.pt, OUT/blend.pt, named RELEASE-blend; SHIP=1
# copies it to bittc_core/weights/bittc_default.pt. The config is the shipped one
# (cpu-small-corr), so the latency does not change.
set -euo pipefail
DATA9=${1:-data/bittc_v9}
OUT=${2:-runs/vru2}
RELEASE=${3:-bittc-2026.12-vru2}
BINARY_STEPS=${BINARY_STEPS:-2000}
CONT_STEPS=${CONT_STEPS:-250}
START=${START:-bittc_core/weights/bittc_default.pt}
mkdir -p "$OUT"
source "$(dirname "$0")/release_steps.sh"
finetune_release "$DATA9" "$OUT" "$RELEASE" 90 --vru-weight 6
