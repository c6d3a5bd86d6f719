# Shell functions the weight recipes share (sourced by docs/train_fovea_weights.sh and
# docs/train_realism_weights.sh).

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
