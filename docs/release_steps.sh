# Shell functions the weight recipes share (sourced by docs/train_fovea_weights.sh,
# docs/train_realism_weights.sh, docs/train_realism2_weights.sh, docs/train_vru_weights.sh,
# docs/train_pair3_weights.sh and docs/train_column_weights.sh).
# FRAME_STRIDE (default 1): the data's pairs span that many of the network's frame intervals.
# RECIPE_CONFIG: the model config trained, cpu-small-corr as sourced (not read from the
# environment); a recipe of another config sets it after sourcing. START must be of it.
RECIPE_CONFIG=cpu-small-corr

name_release() {  # name_release SRC DST NAME: SRC's weights as a release named NAME
    python -c "import sys; from bittc_core.checkpoint import load_checkpoint, release_payload, save_checkpoint
p = release_payload(load_checkpoint(sys.argv[1], map_location='cpu')); p['train_meta']['release'] = sys.argv[3]
save_checkpoint(sys.argv[2], p)" "$1" "$2" "$3"
}

finish_release() {  # finish_release START OUT RELEASE: OUT/continuous.pt named RELEASE, its mean with START
    # named RELEASE-blend (OUT/blend.pt); SHIP=1 copies the blend to the shipped weights
    name_release "$2/continuous.pt" "$2/release.pt" "$3"
    bittc weights average --out "$2/blend.tmp.pt" "$1" "$2/release.pt"
    name_release "$2/blend.tmp.pt" "$2/blend.pt" "$3-blend" && rm "$2/blend.tmp.pt"
    if [ "${SHIP:-0}" = 1 ]; then
        cp "$2/blend.pt" bittc_core/weights/bittc_default.tmp.pt && mv bittc_core/weights/bittc_default.tmp.pt bittc_core/weights/bittc_default.pt
    fi
    echo "wrote $2/release.pt ($3) and $2/blend.pt ($3-blend)"
}

continuous_stage() {  # continuous_stage DATA OUT: the frozen continuous stage on OUT/binary.pt -> OUT/continuous.pt
    bittc train --data "$1" --config "$RECIPE_CONFIG" --stage continuous --freeze-binary --steps "$CONT_STEPS" \
        --frame-stride "${FRAME_STRIDE:-1}" \
        --warmup-steps 50 --seed 0 --lr 2e-4 --val-every 125 --init "$2/binary.pt" --out "$2/continuous.pt"
}

finetune_release() {  # finetune_release DATA OUT RELEASE SEED [FLAG...]: START (kept as OUT/start.pt) fine-tuned
    # on DATA: the binary stage (BINARY_STEPS, lr 5e-5, the in-path actor pixels weighted, FLAG... added), the
    # continuous stage, then the release and its blend with the start (finish_release)
    local data=$1 out=$2 release=$3 seed=$4
    shift 4
    cp "$START" "$out/start.pt"  # the start as it was, whatever SHIP later replaces
    bittc train --data "$data" --config "$RECIPE_CONFIG" --stage binary --steps "$BINARY_STEPS" --seed "$seed" \
        --frame-stride "${FRAME_STRIDE:-1}" \
        --lr 5e-5 --warmup-steps 100 --val-every 500 --val-limit 256 --lovasz-weight 0.5 --actor-weight 2 \
        --inpath-weight 4 "$@" --lr-mult segnet.corr_=10 --init "$out/start.pt" --out "$out/binary.pt"
    continuous_stage "$data" "$out"
    finish_release "$out/start.pt" "$out" "$release"
}
