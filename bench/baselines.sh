#!/usr/bin/env bash
# Every headline row of docs/results.md as a cross-validation under the published protocol (4
# validation folds, test on fold 4) repeated over SEEDS, on both shipped data sets. Each row
# resumes where it stopped, so the script can be rerun; `python3 bench/comparison.py` then prints
# the tables from the runs.
#
#   bash bench/baselines.sh [ROW ...]      SEEDS=0,1,2 JOBS=2 by default
#
# Rows (each for -icub and -biotac):
#   rpp       PVT³ unpruned, then persistent random pruning of 20 % of every weight matrix
#   masks     PVT³ with trained selection masks (--l1 0.25 --mask-lr 10), then 50 % of its frames pruned
#   prunings  the masks row's runs pruned further (after masks): 50 % and 60 % of channels, 30 % and
#             70 % of frames, 50 % of channels and 50 % of frames (LEVELS="channels50 channels60
#             frames30 frames70 channels50-frames50" picks some); 20 epochs of fine-tuning each
#   unpruned-prunings  the rpp row's unpruned runs (masks trained without L1) pruned by their mask
#             scores (after rpp): 60 % of channels by default (LEVELS picks others), 20 epochs each
#   rp        PVT³ with per-step random pruning of 5 % of every weight matrix (--random-prune 0.05)
#   vit, raec the paper's baselines
#   joint     joint learning as Gao et al. (--joint): the set's PVT³ trained beside the other
#             set's, their encodings pulled together after 20 epochs; each network then pruned
#             to 60 % of channels alone (20 epochs of fine-tuning). joint-icub reports both sensors
#             (runs/cv-joint-icub/cv.json, its partner the BioTac networks); not in the default list
#   joint-shared  the same with one temporal transformer for both networks (--joint-share-temporal)
#   raec-published  RAEC with Gao et al.'s decoder (zeros in, its state mapped from the code:
#             decoder_from_state) and training: Adam at a constant 5e-4 (no warm-up, decay,
#             weight decay, label smoothing, dropout, clipping or augmentation) for EPOCHS (2000,
#             theirs); not in the default list. The rate is constant, so the run's first E epochs
#             are the run of E epochs: bench/epochs_curve.py reads the test accuracy that
#             selection by validation gives after every E from one long run's metrics
#
# Rows tried to push accuracy (docs/results.md, "Pushing accuracy"; not in the default list), each
# on the best pruning route of its set, pruned to 60 % of channels with 20 epochs of fine-tuning:
# on iCub the masks trained without L1, on BioTac the trained masks (--l1 0.25 --mask-lr 10):
#   e300      300 epochs instead of 100 (the PVT³ report's protocol)
#   ema       weight averaging, --ema 0.995
#   mixup     --mixup 0.2
#   shift     random time shifts of up to ±20 frames, --aug-shift 20
#   e300-mixup     300 epochs with --mixup 0.2
#   e300-mixup0.4  300 epochs with --mixup 0.4
#   spectral  with a spectral head of 16 bands (--set spectral_bands=16): each channel's level and
#             log band powers, standardised, mapped linearly to logits added to the transformer's
#   spectral-mixup  the same with --mixup 0.2
#   spectral-anytime  the spectral row trained for early answers too (--prefix-training 0.8): the
#             head reads the frames received so far, so its provisional answers and the
#             cross-validation's stopping rule (docs/anytime.md) apply
#   spectral-anytime0.3  the same with --prefix-training 0.3
#   spectral-anytime-mixup  the same with --prefix-training 0.5 --mixup 0.2
#   anytime   trained for early answers too (--prefix-training 0.5), without the spectral head
#   anytime-chscale  the anytime row with each channel's readings scaled by a factor of its own
#             (--aug-channel-scale 0.05, docs/robustness.md)
#   spectral-anytime-mixup-chscale  the spectral-anytime-mixup row with --aug-channel-scale 0.05
#   e300-spectral-anytime-mixup  the spectral-anytime-mixup row trained 300 epochs
#   e300-distill-spectral-anytime-mixup  the distill-spectral-anytime-mixup row trained 300 epochs
#   e300-anytime  the anytime row trained 300 epochs
#   distill-spectral-anytime-mixup  the spectral-anytime-mixup row taught by the spectral row's
#             runs of its split (--distill runs/cv-spectral-SET, after spectral): each batch's
#             targets include their averaged answers to the whole window
#   distill-anytime  the anytime row taught by its own row's runs of its split (--distill
#             runs/cv-anytime-SET, after anytime)
#   extrapolate  same-class extrapolation in training (--extrapolate 1, docs/robustness.md)
#   extrapolate-levels  the same, each channel's level only (--extrapolate 1 --extrapolate-levels)
#   spectral-prunings  the spectral row's trained runs pruned further (after spectral): 70 % of
#             channels, and 50 % of channels with 50 % of frames (LEVELS picks)
#   e300-mixup-prunings  the e300-mixup row's trained runs pruned otherwise (after e300-mixup), as
#             the prunings row does: 60 % of channels with 100 epochs of fine-tuning, and 70 % of
#             channels (LEVELS picks; a level NAME-ftN fine-tunes N epochs instead of 20)
#
# One thread per run (one is as fast as two for these models); JOBS runs side by side.
# PVT3=path/to/pvt3 picks the binary.
set -euo pipefail
cd "$(dirname "$0")/.."
pvt3=${PVT3:-target/release/pvt3}
[ -x "$pvt3" ] || cargo build --release -p pvt3-trainer
seeds=${SEEDS:-0,1,2} jobs=${JOBS:-2}
rows=("$@")
[ ${#rows[@]} -gt 0 ] || rows=(rpp-biotac unpruned-prunings-biotac masks-biotac prunings-biotac rp-biotac vit-biotac raec-biotac
                                rpp-icub unpruned-prunings-icub masks-icub prunings-icub rp-icub raec-icub vit-icub)

# A row's trained runs pruned further: for each level a cross-validation directory of its own,
# OUT-LEVEL, whose folds start as copies of PARENT's trained runs (so `pvt3 cv --resume` only
# prunes and fine-tunes them, and writes the level's cv.json with its interval). ARGS are the
# options the parent row trained with.
#   prunings SET PARENT_ROW PARENT_DIR OUT DEFAULT_LEVELS ARGS...
prunings() {
    local set=$1 parent_row=$2 parent=$3 prefix=$4 levels=$5 level name run out copy base fine_tune
    shift 5
    for run in "$parent"/seed*/fold?; do
        [ -f "$run/result.json" ] || { echo "$run has not finished: run the $parent_row-$set row first" >&2; exit 1; }
    done
    for name in ${LEVELS:-$levels}; do
        base=${name%-ft*} fine_tune=20
        [ "$base" = "$name" ] || fine_tune=${name##*-ft}
        case $base in
            channels50) level="--prune-channels 50" ;;
            channels60) level="--prune-channels 60" ;;
            channels70) level="--prune-channels 70" ;;
            frames30) level="--prune-frames 30" ;;
            frames70) level="--prune-frames 70" ;;
            channels50-frames50) level="--prune-channels 50 --prune-frames 50" ;;
            *) echo "unknown pruning level $name" >&2; exit 2 ;;
        esac
        out=$prefix-$name
        for run in "$parent"/seed*/fold?; do
            copy=$out/${run#"$parent"/}
            [ -d "$copy" ] || { mkdir -p "$copy" && cp -r "$run/result.json" "$run/metrics.jsonl" "$run/model" "$copy/"; }
        done
        echo "== prunings of $parent_row-$set, $name: $pvt3 --threads 1 cv --data data/${set}20.npz $* $level --fine-tune-epochs $fine_tune --epochs $epochs --out $out --resume"
        # shellcheck disable=SC2086
        "$pvt3" --threads 1 cv --data "data/${set}20.npz" "$@" $level --fine-tune-epochs "$fine_tune" \
            --seeds "$seeds" --epochs "$epochs" --jobs "$jobs" --out "$out" --resume
    done
}

for row in "${rows[@]}"; do
    set=${row##*-}
    data=data/${set}20.npz
    epochs=100
    # The set's best pruning route (its training options), and the tried rows' options: the route
    # pruned to 60 % of channels.
    route=()
    [ "$set" = biotac ] && route=(--l1 0.25 --mask-lr 10)
    tried=(--prune-channels 60 --fine-tune-epochs 20 "${route[@]}")
    case $row in
        rpp-*) args=(--prune-weights 20) ;;
        masks-*) args=(--l1 0.25 --mask-lr 10 --prune-frames 50 --fine-tune-epochs 20) ;;
        prunings-*)
            prunings "$set" masks "runs/cv-masks-$set" "runs/cv-masks-$set" \
                "channels50 channels60 frames30 frames70 channels50-frames50" --l1 0.25 --mask-lr 10
            continue ;;
        unpruned-prunings-*)
            prunings "$set" rpp "runs/cv-rpp-$set" "runs/cv-unpruned-$set" channels60
            continue ;;
        rp-*) args=(--random-prune 0.05) ;;
        joint-shared-icub) args=(--joint data/biotac20.npz --joint-share-temporal --prune-channels 60 --fine-tune-epochs 20) ;;
        joint-icub) args=(--joint data/biotac20.npz --prune-channels 60 --fine-tune-epochs 20) ;;
        joint-biotac) args=(--joint data/icub20.npz --prune-channels 60 --fine-tune-epochs 20) ;;
        vit-*) args=(--model vit) ;;
        # RAEC: Gao et al.'s Adam (AdamW without weight decay), lr 5e-4, batch 32; -published with
        # the rest of their training too (before raec-*, which it would match).
        raec-published-*) args=(--model raec --set decoder_from_state=true --lr 5e-4 --lr-floor 1 --warmup-epochs 0 --weight-decay 0 --label-smoothing 0
                                --dropout 0 --clip-grad 0 --aug-gain 0 --aug-noise 0) epochs=${EPOCHS:-2000} ;;
        raec-*) args=(--model raec --lr 5e-4 --weight-decay 0) ;;
        e300-mixup-prunings-*)
            epochs=300
            prunings "$set" e300-mixup "runs/cv-e300-mixup-$set" "runs/cv-e300-mixup-$set" \
                "channels60-ft100 channels70" "${route[@]}" --mixup 0.2
            continue ;;
        e300-mixup-*) args=("${tried[@]}" --mixup 0.2) epochs=300 ;;
        e300-spectral-anytime-mixup-*) args=("${tried[@]}" --set spectral_bands=16 --prefix-training 0.5 --mixup 0.2) epochs=300 ;;
        e300-distill-spectral-anytime-mixup-*) args=("${tried[@]}" --set spectral_bands=16 --prefix-training 0.5 --mixup 0.2 --distill "runs/cv-spectral-$set") epochs=300 ;;
        e300-anytime-*) args=("${tried[@]}" --prefix-training 0.5) epochs=300 ;;
        e300-mixup0.4-*) args=("${tried[@]}" --mixup 0.4) epochs=300 ;;
        e300-*) args=("${tried[@]}") epochs=300 ;;
        spectral-prunings-*)
            prunings "$set" spectral "runs/cv-spectral-$set" "runs/cv-spectral-$set" \
                "channels70 channels50-frames50" "${route[@]}" --set spectral_bands=16
            continue ;;
        spectral-mixup-*) args=("${tried[@]}" --set spectral_bands=16 --mixup 0.2) ;;
        distill-anytime-*) args=("${tried[@]}" --prefix-training 0.5 --distill "runs/cv-anytime-$set") ;;
        anytime-chscale-*) args=("${tried[@]}" --prefix-training 0.5 --aug-channel-scale 0.05) ;;
        anytime-*) args=("${tried[@]}" --prefix-training 0.5) ;;
        distill-spectral-anytime-mixup-*) args=("${tried[@]}" --set spectral_bands=16 --prefix-training 0.5 --mixup 0.2 --distill "runs/cv-spectral-$set") ;;
        spectral-anytime-mixup-chscale-*) args=("${tried[@]}" --set spectral_bands=16 --prefix-training 0.5 --mixup 0.2 --aug-channel-scale 0.05) ;;
        spectral-anytime-mixup-*) args=("${tried[@]}" --set spectral_bands=16 --prefix-training 0.5 --mixup 0.2) ;;
        spectral-anytime0.3-*) args=("${tried[@]}" --set spectral_bands=16 --prefix-training 0.3) ;;
        spectral-anytime-*) args=("${tried[@]}" --set spectral_bands=16 --prefix-training 0.8) ;;
        spectral-*) args=("${tried[@]}" --set spectral_bands=16) ;;
        ema-*) args=("${tried[@]}" --ema 0.995) ;;
        extrapolate-levels-*) args=("${tried[@]}" --extrapolate 1 --extrapolate-levels) ;;
        extrapolate-*) args=("${tried[@]}" --extrapolate 1) ;;
        mixup-*) args=("${tried[@]}" --mixup 0.2) ;;
        shift-*) args=("${tried[@]}" --aug-shift 20) ;;
        *) echo "unknown row $row" >&2; exit 2 ;;
    esac
    [ -f "$data" ] || { echo "unknown row $row (no $data)" >&2; exit 2; }
    out=runs/cv-$row
    resume=()
    [ -d "$out" ] && resume=(--resume)
    echo "== $row: $pvt3 --threads 1 cv --data $data ${args[*]} --seeds $seeds --epochs $epochs --jobs $jobs --out $out"
    "$pvt3" --threads 1 cv --data "$data" "${args[@]}" --seeds "$seeds" --epochs "$epochs" --jobs "$jobs" --out "$out" "${resume[@]}"
done
