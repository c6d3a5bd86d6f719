#!/usr/bin/env bash
# A fine-tune of the shipped weights on pairs 0.3 s apart: the pair the geofence controller
# feeds the network (frame stride 3 at 10 Hz), averaged with its start.
#
#   1. data: for s in "val 400" "test 400" "train 8000"; do set -- $s; bittc generate --out data/bittc_v11 \
#              --fps 3.333333 --fovea-share 0.4 --vehicle-texture mixed --realism-share 0.5 --realism-codecs jpeg \
#              --vru-share 0.6 --split $1 --samples $2 --seed 11 --workers 2; done
#   2. this script: [START=FILE] [TEACHER=FILE [DISTILL_SCOPE=scenery|scenery-vehicles]] \
#        [FREEZE_NORM_STATS=1] [SHIP=1] bash docs/train_pair3_weights.sh \
#        [DATA_V11] [OUT] [RELEASE]
#      bittc-2026.12-pair3f: FREEZE_NORM_STATS=1 bash docs/train_pair3_weights.sh data/bittc_v11 runs/pair3f \
#        bittc-2026.12-pair3f
#
# bittc_v11 is bittc_v9's recipe (a fovea in 40 % of the samples, half through a sensor,
# road users in 60 % of the scenes) rendered at 3.33 Hz, so that each pair spans 0.3 s:
# the network is read at its 0.1 s interval on such pairs (time compressed 3x), and every
# dataset before saw 0.1 s pairs, where a road user crossing at 1.8 m/s moves a third as
# far. The recipe of docs/train_vru_weights.sh otherwise (START, the steps, the weights,
# the continuous stage, the blend). FREEZE_NORM_STATS=1: the batch norms keep START's running
# statistics (bittc train --freeze-norm-stats), which 0.3 s pairs would otherwise move.
set -euo pipefail
DATA11=${1:-data/bittc_v11}
OUT=${2:-runs/pair3}
RELEASE=${3:-bittc-2026.12-pair3}
BINARY_STEPS=${BINARY_STEPS:-2000}
CONT_STEPS=${CONT_STEPS:-250}
export FRAME_STRIDE=3
START=${START:-bittc_core/weights/bittc_default.pt}
mkdir -p "$OUT"
source "$(dirname "$0")/release_steps.sh"
# TEACHER=FILE: also learn that checkpoint's flip-averaged maps (--teacher, weight DISTILL_WEIGHT, default 1);
# DISTILL_SCOPE=scenery: its maps instead of the ground truth on scenery pixels, the actors' ground truth kept;
# DISTILL_SCOPE=scenery-vehicles: on vehicles too, only the road users learn the ground truth
finetune_release "$DATA11" "$OUT" "$RELEASE" 90 --vru-weight 6 \
    ${TEACHER:+--teacher "$TEACHER" --distill-weight "${DISTILL_WEIGHT:-1}"} \
    ${DISTILL_SCOPE:+--distill-scope "$DISTILL_SCOPE"} \
    $([ "${FREEZE_NORM_STATS:-0}" = 1 ] && echo --freeze-norm-stats)
