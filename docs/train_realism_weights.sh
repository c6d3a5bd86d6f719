#!/usr/bin/env bash
# A fine-tune of the shipped weights on images through the camera sensor model (docs/sensor.md),
# averaged with its start.
#
#   1. data: bittc generate --out data/bittc_v7 --fovea-share 0.5 --vehicle-texture mixed --realism-share 0.5 --realism-codecs jpeg --split val   --samples 400  --seed 7 --workers 2
#            bittc generate --out data/bittc_v7 --fovea-share 0.5 --vehicle-texture mixed --realism-share 0.5 --realism-codecs jpeg --split train --samples 8000 --seed 7 --workers 2
#   2. this script: [START=FILE] [SHIP=1] bash docs/train_realism_weights.sh [DATA_V7] [OUT] [RELEASE]
#
# START is the shipped bittc-2026.12-fovea2-blend (bittc_core/weights/bittc_default.pt) by
# default. bittc_v7 is bittc_v6's recipe (half the samples through a fovea, vehicles plain or
# textured) with half of its clips through a sensor drawn per clip. One binary run with the
# in-path vehicle pixels weighted (the checkpoint kept is the best by validation mIoU, on a
# validation split half through a sensor too), then the frozen continuous stage; its best
# checkpoint is written to OUT/release.pt with its release name. Last, the blend: the
# element-wise mean of START and OUT/release.pt, OUT/blend.pt, named RELEASE-blend; SHIP=1
# copies it to bittc_core/weights/bittc_default.pt. The config is the shipped one
# (cpu-small-corr), so the latency does not change.
set -euo pipefail
DATA7=${1:-data/bittc_v7}
OUT=${2:-runs/realism1}
RELEASE=${3:-bittc-2026.12-realism1}
BINARY_STEPS=${BINARY_STEPS:-1500}
CONT_STEPS=${CONT_STEPS:-250}
START=${START:-bittc_core/weights/bittc_default.pt}
mkdir -p "$OUT"
source "$(dirname "$0")/release_steps.sh"
finetune_release "$DATA7" "$OUT" "$RELEASE" 70
