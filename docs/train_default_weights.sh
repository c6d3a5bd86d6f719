#!/usr/bin/env bash
# Reproduce bittc-2026.11, the base of the shipped weights (docs/train_fovea_weights.sh
# fine-tunes it for the fovea and ships the blend), on a CPU (or a GPU with --device cuda
# appended to each train command).
#   1. data:  bittc generate --out data/bittc_v1 --ground-texture smooth --split {val,test,train} ...
#             bittc generate --out data/bittc_v2 --split {val,test,train} ...   (see README)
#   2. this:  bash docs/train_default_weights.sh data/bittc_v1 data/bittc_v2 runs/default
# Stages as in the paper: binary-flow pre-training, binary TTC with binary flow as the
# auxiliary task (0.8 / 0.2; run four times, each run restarting the learning-rate
# schedule from the previous run's best weights; the third and fourth add a Lovasz surrogate
# of the per-image two-class IoU to the BCE), all on bittc_v1 (smooth ground); a fifth and a
# sixth binary run on bittc_v2 (the same scenes with the detailed ground; the sixth at half the
# learning rate, vehicle pixels, moving or not, weighted 2 in the loss), then the continuous stage with the
# binary network frozen (--freeze-binary: only the continuous refinement learns, SmoothL1 on the refined log eta;
# end to end, BCE 0.1 + SmoothL1 0.9 as in the paper, this small model lost 0.05 mIoU);
# then a seventh binary run from that checkpoint (the sixth's settings, 4,000 steps, seed 9)
# and a shorter frozen continuous stage on it; then config cpu-small-corr grown from that
# (the correlation volume, starting at zero), three more binary runs (the second and the
# third with the correlation convs at 10x the learning rate, --lr-mult) and a frozen
# continuous stage; then a fourth correlation run from that, keeping the weights of every
# validation step (--keep-checkpoints), the mean of its last three (bittc weights average)
# and a last, shorter frozen continuous stage on that mean, whose best checkpoint ships.
set -euo pipefail
DATA=${1:-data/bittc_v1}
DATA2=${2:-data/bittc_v2}
OUT=${3:-runs/default}
FLOW_STEPS=${FLOW_STEPS:-600}
BINARY_STEPS=${BINARY_STEPS:-6000}
BINARY2_STEPS=${BINARY2_STEPS:-7000}
BINARY3_STEPS=${BINARY3_STEPS:-5000}
BINARY4_STEPS=${BINARY4_STEPS:-5000}
GROUND_STEPS=${GROUND_STEPS:-5000}
ACTOR_STEPS=${ACTOR_STEPS:-4000}
CONT_STEPS=${CONT_STEPS:-1000}
SEVENTH_STEPS=${SEVENTH_STEPS:-4000}
CONT7_STEPS=${CONT7_STEPS:-500}
CORR_STEPS=${CORR_STEPS:-4000}
CORR2_STEPS=${CORR2_STEPS:-4000}
CORR3_STEPS=${CORR3_STEPS:-4000}
CONT_CORR_STEPS=${CONT_CORR_STEPS:-500}
CORR4_STEPS=${CORR4_STEPS:-3000}
CONT_MEAN_STEPS=${CONT_MEAN_STEPS:-250}
mkdir -p "$OUT"
bittc train --data "$DATA" --config cpu-small --stage flow --steps "$FLOW_STEPS" --seed 0 --out "$OUT/flow.pt"
bittc train --data "$DATA" --config cpu-small --stage binary --steps "$BINARY_STEPS" --seed 0 --init "$OUT/flow.pt" --out "$OUT/binary.pt"
bittc train --data "$DATA" --config cpu-small --stage binary --steps "$BINARY2_STEPS" --seed 2 --lr 2e-4 --val-every 500 --init "$OUT/binary.pt" --out "$OUT/binary2.pt"
bittc train --data "$DATA" --config cpu-small --stage binary --steps "$BINARY3_STEPS" --seed 3 --lr 2e-4 --val-every 1000 --val-limit 256 --lovasz-weight 0.5 --init "$OUT/binary2.pt" --out "$OUT/binary3.pt"
bittc train --data "$DATA" --config cpu-small --stage binary --steps "$BINARY4_STEPS" --seed 4 --lr 2e-4 --val-every 1000 --val-limit 256 --lovasz-weight 0.5 --init "$OUT/binary3.pt" --out "$OUT/binary4.pt"
bittc train --data "$DATA2" --config cpu-small --stage binary --steps "$GROUND_STEPS" --seed 7 --lr 2e-4 --val-every 1000 --val-limit 256 --lovasz-weight 0.5 --init "$OUT/binary4.pt" --out "$OUT/binary_ground.pt"
bittc train --data "$DATA2" --config cpu-small --stage binary --steps "$ACTOR_STEPS" --seed 8 --lr 1e-4 --val-every 1000 --val-limit 256 --lovasz-weight 0.5 --actor-weight 2 --init "$OUT/binary_ground.pt" --out "$OUT/binary_actor.pt"
bittc train --data "$DATA2" --config cpu-small --stage continuous --freeze-binary --steps "$CONT_STEPS" --seed 0 --lr 5e-4 --val-every 250 --init "$OUT/binary_actor.pt" --out "$OUT/continuous.pt"
bittc train --data "$DATA2" --config cpu-small --stage binary --steps "$SEVENTH_STEPS" --seed 9 --lr 1e-4 --val-every 1000 --val-limit 256 --lovasz-weight 0.5 --actor-weight 2 --init "$OUT/continuous.pt" --out "$OUT/binary7.pt"
bittc train --data "$DATA2" --config cpu-small --stage continuous --freeze-binary --steps "$CONT7_STEPS" --seed 0 --lr 2e-4 --val-every 125 --init "$OUT/binary7.pt" --out "$OUT/continuous7.pt"
# the correlation volume (cpu-small-corr, its convs starting at zero), then once more with
# those convs at 10x the learning rate, twice, then the frozen continuous stage on that
bittc train --data "$DATA2" --config cpu-small-corr --stage binary --steps "$CORR_STEPS" --seed 13 --lr 1e-4 --val-every 1000 --val-limit 256 --lovasz-weight 0.5 --actor-weight 2 --init "$OUT/continuous7.pt" --out "$OUT/corr.pt"
bittc train --data "$DATA2" --config cpu-small-corr --stage binary --steps "$CORR2_STEPS" --seed 14 --lr 1e-4 --val-every 1000 --val-limit 256 --lovasz-weight 0.5 --actor-weight 2 --lr-mult segnet.corr_=10 --init "$OUT/corr.pt" --out "$OUT/corr2.pt"
bittc train --data "$DATA2" --config cpu-small-corr --stage binary --steps "$CORR3_STEPS" --seed 15 --lr 1e-4 --val-every 1000 --val-limit 256 --lovasz-weight 0.5 --actor-weight 2 --lr-mult segnet.corr_=10 --init "$OUT/corr2.pt" --out "$OUT/corr3.pt"
bittc train --data "$DATA2" --config cpu-small-corr --stage continuous --freeze-binary --steps "$CONT_CORR_STEPS" --seed 0 --lr 2e-4 --val-every 125 --init "$OUT/corr3.pt" --out "$OUT/continuous_corr.pt"
# a fourth correlation run (its validation steps at 1/4, 2/4, 3/4 and 4/4 of the run kept),
# the mean of the last three, and the frozen continuous stage on that mean
CORR4_VAL=$((CORR4_STEPS / 4))
bittc train --data "$DATA2" --config cpu-small-corr --stage binary --steps "$CORR4_STEPS" --seed 20 --lr 1e-4 --val-every "$CORR4_VAL" --val-limit 256 --lovasz-weight 0.5 --actor-weight 2 --lr-mult segnet.corr_=10 --keep-checkpoints --init "$OUT/continuous_corr.pt" --out "$OUT/corr4.pt"
bittc weights average $(for k in 2 3 4; do printf '%s/corr4.binary.step%06d.pt ' "$OUT" $((k * CORR4_VAL)); done) --out "$OUT/corr4_mean.pt"
bittc train --data "$DATA2" --config cpu-small-corr --stage continuous --freeze-binary --steps "$CONT_MEAN_STEPS" --warmup-steps 50 --seed 0 --lr 2e-4 --val-every 125 --init "$OUT/corr4_mean.pt" --out "$OUT/continuous_mean.pt"
# the continuous stage's best checkpoint (by val MiD; the binary part is the same in all) is
# the release bittc-2026.11, the start of the shipped fovea fine-tune and blend
python -c "import sys; from bittc_core.checkpoint import load_checkpoint, release_payload, save_checkpoint
p = release_payload(load_checkpoint(sys.argv[1], map_location='cpu')); p['train_meta']['release'] = 'bittc-2026.11'
save_checkpoint(sys.argv[2], p)" "$OUT/continuous_mean.pt" "$OUT/release.pt"
echo "wrote $OUT/release.pt (bittc-2026.11); next: START=$OUT/release.pt SHIP=1 bash docs/train_fovea_weights.sh"
