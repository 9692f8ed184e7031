#!/usr/bin/env bash
# Touched any way (docs/robustness.md): pvt3 trained with whole levels of a touch condition held
# out, on the public FabricSlide set (7 fabrics, forces F120–F250, speeds ±10–150 mm/s), imported
# from its CSV files as a user would. Each row is a cross-validation (4 validation folds × SEEDS)
# whose test set is the held-out touches; the row `random` is the plain stratified split.
#
#   bash bench/robustness.sh FABRICSLIDE [ROW ...]     # FABRICSLIDE: a checkout of wngfra/FabricSlide
#
# Rows:
#   random            stratified folds, nothing held out
#   speeds-beyond     speeds 10 and 150 mm/s (both directions): slower and faster than any trained
#   speeds-between    speeds 20 and 100 mm/s (both directions): between trained speeds
#   forces-unseen     forces F210 and F250 (F120–F180 trained)
#   speed-V           one speed V in turn (10 20 50 100 120 150), both directions
#   force-F           one force F in turn (120 150 180 210 250)
#   direction-forward, direction-back   every touch of one sliding direction
#   direction-forward-FABRIC, direction-back-FABRIC   one fabric's touches of that direction (the
#                     others train both ways), e.g. direction-forward-Canvas
# Default: random speeds-beyond speeds-between forces-unseen.
#
# VARIANT=NAME (default `plain`) names the runs' folder, target/robustness/NAME/ROW; IMPORT holds
# extra options of `pvt3 import` (e.g. `--per-distance speed=150`), TRAIN extra options of `pvt3 cv`
# (e.g. `--aug-stretch 0.5`); a variant trains with `--robust off` unless TRAIN says `--robust`,
# as every variant did before `--robust auto` was pvt3's default (TRAIN="--robust auto" is that
# default). SEEDS=0,1,2 JOBS=2 by default: every seed's four validation folds.
# FOLDS=0 (or any list) trains only those validation folds of each seed, one `pvt3 cv --only` run
# each, side by side by JOBS: a quicker look, which the table marks. Rows resume where they stopped.
# `python3 bench/robustness_report.py target/robustness` prints the tables of docs/robustness.md.
set -euo pipefail
set -f # IMPORT and TRAIN hold patterns for pvt3 (--columns channel*), not for the shell
cd "$(dirname "$0")/.."
src=${1:?usage: bash bench/robustness.sh FABRICSLIDE [ROW ...]}
shift
[ -d "$src/data/fabric" ] || { echo "$src/data/fabric: no such folder (a checkout of wngfra/FabricSlide)" >&2; exit 1; }
pvt3=${PVT3:-target/release/pvt3}
[ -n "${PVT3:-}" ] || cargo build -q --release -p pvt3-trainer
seeds=${SEEDS:-0,1,2} jobs=${JOBS:-2} variant=${VARIANT:-plain} folds=${FOLDS:-}
train=${TRAIN:-}
[[ $train == *--robust* ]] || train="--robust off $train"
out=target/robustness/$variant
mkdir -p "$out"
# shellcheck disable=SC2086 # IMPORT and TRAIN are word lists of options
[ -e "$out/fabric.npz" ] || "$pvt3" import "$src/data/fabric" --name '{class}_F{force}_V{speed}mmps_*' --out "$out/fabric.npz" ${IMPORT:-} | tee "$out/import.txt"

hold() {
  case $1 in
    random) ;;
    speeds-beyond) echo "--hold-out speed=10,-10,150,-150" ;;
    speeds-between) echo "--hold-out speed=20,-20,100,-100" ;;
    forces-unseen) echo "--hold-out force=210,250" ;;
    speed-*) echo "--hold-out speed=${1#speed-},-${1#speed-}" ;;
    force-*) echo "--hold-out force=${1#force-}" ;;
    direction-forward) echo "--hold-out speed=10,20,50,100,120,150" ;;
    direction-back) echo "--hold-out speed=-10,-20,-50,-100,-120,-150" ;;
    direction-forward-* | direction-back-*)
      echo "$(hold "${1%-*}") --hold-out-class ${1##*-}" ;;
    *) echo "unknown row $1" >&2; return 1 ;;
  esac
}

rows=("$@")
[ ${#rows[@]} -gt 0 ] || rows=(random speeds-beyond speeds-between forces-unseen)
failed=()
for row in "${rows[@]}"; do
  args=$(hold "$row")
  echo "== $variant $row: pvt3 cv $args $train"
  resume=
  [ ! -d "$out/$row" ] || resume=--resume
  if [ -z "$folds" ]; then
    # shellcheck disable=SC2086
    "$pvt3" cv --data "$out/fabric.npz" --seeds "$seeds" --jobs "$jobs" --out "$out/$row" $args $train $resume | tail -n 4 || failed+=("$row")
    continue
  fi
  # Some folds of each seed, JOBS at a time; then the report of all of them.
  for seed in ${seeds//,/ }; do
    for fold in ${folds//,/ }; do
      while [ "$(jobs -rp | wc -l)" -ge "$jobs" ]; do wait -n || true; done
      # shellcheck disable=SC2086
      "$pvt3" cv --data "$out/fabric.npz" --only "seed=$seed,fold=$fold" --out "$out/$row" $args $train --resume >/dev/null 2>>"$out/$row.log" &
    done
  done
  wait
  # A row that cannot run (a class with no touch left to train on, say) is said, and the others go on.
  if ! "$pvt3" cv --report "$out/$row" 2>/dev/null | tail -n 4; then
    echo "$row did not run: $(grep -m1 '^Error' "$out/$row.log")" >&2
    failed+=("$row")
  fi
done
[ ${#failed[@]} -eq 0 ] || { echo "rows that did not run: ${failed[*]}" >&2; exit 1; }
