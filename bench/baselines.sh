#!/usr/bin/env bash
# The comparison rows of docs/results.md: the paper's ViT and RAEC baselines and PVT³ trained with
# random unstructured pruning, each by `pvt3 cv` under the published protocol (4 folds, test on
# fold 4), on both shipped data sets. The PVT³ rows themselves come from the runs named in
# docs/results.md. Each cross-validation resumes where it stopped, so the script can be rerun.
#
#   bash bench/baselines.sh [ROW ...]     rows: raec-icub vit-biotac raec-biotac vit-icub rp-icub rp-biotac
#
# One thread per run (one is as fast as two for these models); JOBS=2 trains two folds side by side;
# PVT3=path/to/pvt3 picks the binary.
set -euo pipefail
cd "$(dirname "$0")/.."
pvt3=${PVT3:-target/release/pvt3}
[ -x "$pvt3" ] || cargo build --release -p pvt3-trainer
rows=("$@")
[ ${#rows[@]} -gt 0 ] || rows=(raec-icub vit-biotac raec-biotac vit-icub rp-icub rp-biotac)
for row in "${rows[@]}"; do
    case $row in
        # RAEC as Gao et al. train it: Adam (AdamW without weight decay), lr 5e-4, batch 32.
        raec-icub) args=(--data data/icub20.npz --model raec --lr 5e-4 --weight-decay 0) ;;
        raec-biotac) args=(--data data/biotac20.npz --model raec --lr 5e-4 --weight-decay 0) ;;
        vit-icub) args=(--data data/icub20.npz --model vit) ;;
        vit-biotac) args=(--data data/biotac20.npz --model vit) ;;
        rp-icub) args=(--data data/icub20.npz --random-prune 0.05) ;;
        rp-biotac) args=(--data data/biotac20.npz --random-prune 0.05) ;;
        *) echo "unknown row $row" >&2; exit 2 ;;
    esac
    out=runs/cv-$row
    resume=()
    [ -d "$out" ] && resume=(--resume)
    echo "== $row: $pvt3 --threads 1 cv ${args[*]} --seeds 0 --epochs 100 --out $out"
    "$pvt3" --threads 1 cv "${args[@]}" --seeds 0 --epochs 100 --jobs "${JOBS:-1}" --out "$out" "${resume[@]}"
done
