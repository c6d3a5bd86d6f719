#!/usr/bin/env bash
# The braking fine-tune of the shipped weights: what a collision-warning camera must fence.
#
#   1. data: bittc generate --out data/bittc_v4 --ahead-share 0.4 --split val   --samples 500   --seed 0 --workers 2
#            bittc generate --out data/bittc_v4 --ahead-share 0.4 --split train --samples 12000 --seed 0 --workers 2
#   2. this script: bash docs/train_braking_weights.sh [DATA_V4] [OUT] [RELEASE]
#
# From the shipped release (bittc_core/weights/bittc_default.pt, or START), one binary run on
# bittc_v4 (40 % of its samples a braking case ahead: a vehicle in or near the ego's lane at
# 0.3-4 s TTC) with the in-path vehicle pixels weighted, then the frozen continuous stage;
# the continuous stage's best checkpoint is written to OUT/release.pt with its release name.
set -euo pipefail
DATA4=${1:-data/bittc_v4}
OUT=${2:-runs/braking}
RELEASE=${3:-bittc-2026.12-braking}
START=${START:-bittc_core/weights/bittc_default.pt}
BRAKING_STEPS=${BRAKING_STEPS:-1500}
CONT_STEPS=${CONT_STEPS:-250}
mkdir -p "$OUT"
bittc train --data "$DATA4" --config cpu-small-corr --stage binary --steps "$BRAKING_STEPS" --seed 40 --lr 1e-4 \
    --val-every 500 --val-limit 256 --lovasz-weight 0.5 --actor-weight 2 --inpath-weight 4 --lr-mult segnet.corr_=10 \
    --init "$START" --out "$OUT/binary.pt"
bittc train --data "$DATA4" --config cpu-small-corr --stage continuous --freeze-binary --steps "$CONT_STEPS" \
    --warmup-steps 50 --seed 0 --lr 2e-4 --val-every 125 --init "$OUT/binary.pt" --out "$OUT/continuous.pt"
python -c "import sys; from bittc_core.checkpoint import load_checkpoint, release_payload, save_checkpoint
p = release_payload(load_checkpoint(sys.argv[1], map_location='cpu')); p['train_meta']['release'] = sys.argv[3]
save_checkpoint(sys.argv[2], p)" "$OUT/continuous.pt" "$OUT/release.pt" "$RELEASE"
echo "wrote $OUT/release.pt ($RELEASE); ship it with: cp $OUT/release.pt bittc_core/weights/bittc_default.pt"
