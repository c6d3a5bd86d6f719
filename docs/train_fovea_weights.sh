#!/usr/bin/env bash
# The shipped weights bittc-2026.12-fovea2-blend: the fovea fine-tune of bittc-2026.11, one
# network for both views (shared weights), averaged with its start.
#
#   1. data: bittc generate --out data/bittc_v6 --fovea-share 0.5 --vehicle-texture mixed --split val   --samples 400  --seed 6 --workers 2
#            bittc generate --out data/bittc_v6 --fovea-share 0.5 --vehicle-texture mixed --split train --samples 8000 --seed 6 --workers 2
#   2. this script: [START=FILE] [SHIP=1] bash docs/train_fovea_weights.sh [DATA_V6] [OUT] [RELEASE]
#
# START is bittc-2026.11: by default its file as committed in 71b3ae1 (git history), or the
# one docs/train_default_weights.sh writes (START=runs/default/release.pt). One binary run on
# bittc_v6 (half its samples seen through a fovea of 5-16 deg vertical field of view: a far
# target in or near the ego's lane, threats and look-alikes that close on no one; the other
# half today's random wide scenes; vehicles plain or textured) with the in-path vehicle pixels
# weighted (the checkpoint kept is the best by validation mIoU), then the frozen continuous
# stage; its best checkpoint is written to OUT/release.pt with its release name. Last, the
# blend: the element-wise mean of START and OUT/release.pt (weight-space ensembling),
# OUT/blend.pt, named RELEASE-blend; SHIP=1 copies it to bittc_core/weights/bittc_default.pt.
# The config is the shipped one (cpu-small-corr).
set -euo pipefail
DATA6=${1:-data/bittc_v6}
OUT=${2:-runs/fovea2}
RELEASE=${3:-bittc-2026.12-fovea2}
FOVEA_STEPS=${FOVEA_STEPS:-2000}
CONT_STEPS=${CONT_STEPS:-250}
mkdir -p "$OUT"
source "$(dirname "$0")/release_steps.sh"
if [ -z "${START:-}" ]; then  # bittc-2026.11 from the git history
    git show 71b3ae1:bittc_core/weights/bittc_default.pt > "$OUT/start.tmp.pt"
    START="$OUT/start.pt"
    name_release "$OUT/start.tmp.pt" "$START" bittc-2026.11 && rm "$OUT/start.tmp.pt"
fi
bittc train --data "$DATA6" --config cpu-small-corr --stage binary --steps "$FOVEA_STEPS" --seed 60 --lr 1e-4 \
    --val-every 500 --val-limit 256 --lovasz-weight 0.5 --actor-weight 2 --inpath-weight 4 --lr-mult segnet.corr_=10 \
    --init "$START" --out "$OUT/binary.pt"
continuous_stage "$DATA6" "$OUT"
finish_release "$START" "$OUT" "$RELEASE"
