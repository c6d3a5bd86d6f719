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
name_release() {  # name_release SRC DST NAME: SRC's weights as a release named NAME
    python -c "import sys; from bittc_core.checkpoint import load_checkpoint, release_payload, save_checkpoint
p = release_payload(load_checkpoint(sys.argv[1], map_location='cpu')); p['train_meta']['release'] = sys.argv[3]
save_checkpoint(sys.argv[2], p)" "$1" "$2" "$3"
}
if [ -z "${START:-}" ]; then  # bittc-2026.11 from the git history
    git show 71b3ae1:bittc_core/weights/bittc_default.pt > "$OUT/start.tmp.pt"
    START="$OUT/start.pt"
    name_release "$OUT/start.tmp.pt" "$START" bittc-2026.11 && rm "$OUT/start.tmp.pt"
fi
bittc train --data "$DATA6" --config cpu-small-corr --stage binary --steps "$FOVEA_STEPS" --seed 60 --lr 1e-4 \
    --val-every 500 --val-limit 256 --lovasz-weight 0.5 --actor-weight 2 --inpath-weight 4 --lr-mult segnet.corr_=10 \
    --init "$START" --out "$OUT/binary.pt"
bittc train --data "$DATA6" --config cpu-small-corr --stage continuous --freeze-binary --steps "$CONT_STEPS" \
    --warmup-steps 50 --seed 0 --lr 2e-4 --val-every 125 --init "$OUT/binary.pt" --out "$OUT/continuous.pt"
name_release "$OUT/continuous.pt" "$OUT/release.pt" "$RELEASE"
bittc weights average --out "$OUT/blend.tmp.pt" "$START" "$OUT/release.pt"
name_release "$OUT/blend.tmp.pt" "$OUT/blend.pt" "$RELEASE-blend" && rm "$OUT/blend.tmp.pt"
if [ "${SHIP:-0}" = 1 ]; then
    cp "$OUT/blend.pt" bittc_core/weights/bittc_default.tmp.pt && mv bittc_core/weights/bittc_default.tmp.pt bittc_core/weights/bittc_default.pt
fi
echo "wrote $OUT/release.pt ($RELEASE) and $OUT/blend.pt ($RELEASE-blend)"
