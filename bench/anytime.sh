#!/usr/bin/env bash
# docs/anytime.md and docs/anytime.svg: provisional answers, measured. For each data set and
# seed, trains PVT³ on whole windows and with --prefix-training P (validation fold 0, test fold
# 4, the trainer's defaults otherwise), reads `pvt3 eval RUN --anytime --json` on the test fold
# (accuracy from the first 10 %, 20 % … of each touch; the stopping rule calibrated on the
# validation fold, applied to the test fold), and times a provisional answer at 10, 50 and 100 %
# of a touch in the runtime (`pvt3-run --bench` on the exported file).
#
#   bash bench/anytime.sh                        # SEEDS="0 1 2" P=0.5 JOBS=2 DATASETS="icub20 biotac20"
#   SEEDS="0 1 2 3 4" P=0.3 bash bench/anytime.sh
#   DATASETS=biotac20 P=0.8 EXTRA="--mixup 0.2" bash bench/anytime.sh   # more trainer options, both variants
#
# Runs go to runs/anytime/DATA-VARIANT[-EXTRA]-sSEED, EXTRA without its spaces and dashes (a finished
# run is not trained again).
set -euo pipefail
cd "$(dirname "$0")/.."
SEEDS=${SEEDS:-"0 1 2"} P=${P:-0.5} JOBS=${JOBS:-2} DATASETS=${DATASETS:-"icub20 biotac20"} EXTRA=${EXTRA:-}
tag=$(printf %s "$EXTRA" | tr -d ' -')
[ -z "$tag" ] || tag=-$tag
out=runs/anytime
mkdir -p "$out"
# The run of data set $1, variant $2 (whole or prefixP), seed $3.
run_dir() { printf %s "$out/$1-$2$tag-s$3"; }
cargo build -q --release -p pvt3-trainer -p pvt3-runtime --bins
pvt3=target/release/pvt3

# One training per line: data set, variant, seed. Finished runs are skipped.
jobs_file=$(mktemp)
trap 'rm -f "$jobs_file"' EXIT
for data in $DATASETS; do
  for seed in $SEEDS; do
    for variant in whole "prefix$P"; do
      [ -f "$(run_dir "$data" "$variant" "$seed")/result.json" ] || echo "$data $variant $seed" >> "$jobs_file"
    done
  done
done
train_one() {
  local data=$1 variant=$2 seed=$3 run
  run=$(run_dir "$@")
  local prefix=0
  [ "$variant" = whole ] || prefix=$P
  rm -rf "$run"
  # shellcheck disable=SC2086  # EXTRA is a list of options
  "$pvt3" --threads 1 train --data "data/$data.npz" --seed "$seed" --prefix-training "$prefix" $EXTRA --out "$run" \
    --export "$run.onnx" > "$run.log" 2>&1
  echo "trained $run: $(grep 'best epoch' "$run.log")" >&2
}
export -f train_one run_dir
export out P pvt3 EXTRA tag
echo "$(wc -l < "$jobs_file") trainings, $JOBS at a time" >&2
xargs -r -P "$JOBS" -L 1 bash -c 'train_one "$@"' _ < "$jobs_file"

results=$out/anytime.jsonl
: > "$results"
for data in $DATASETS; do
  for seed in $SEEDS; do
    for variant in whole "prefix$P"; do
      run=$(run_dir "$data" "$variant" "$seed")
      "$pvt3" eval "$run" --anytime --json | sed "s/^{/{\"data\":\"$data\",\"variant\":\"$variant\",\"seed\":$seed,/" >> "$results"
    done
  done
done
# A provisional answer's cost in the runtime, on the first seed's prefix-trained files.
first=${SEEDS%% *}
costs=$out/peek-cost.jsonl
: > "$costs"
for data in $DATASETS; do
  env -u RUST_BACKTRACE target/release/pvt3-run --bench "$(run_dir "$data" "prefix$P" "$first").onnx" 1 1 >> "$costs"
done
python3 bench/anytime_report.py "$results" "$costs" "$P" "$SEEDS"
