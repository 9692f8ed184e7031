#!/usr/bin/env bash
# Submits the cross-validation protocol to Slurm: a job array of SEEDS × 4 runs
# (bench/slurm/cv.sbatch) into OUT, and a job that runs `pvt3 cv --report OUT` once every task
# has ended, finished or not. Prints the two job ids.
#
#   bash bench/slurm/submit.sh SEEDS OUT [pvt3 cv options…]
#   bash bench/slurm/submit.sh 5 runs/cv-icub --data data/icub20.npz --epochs 300
#
# Build first (cargo build --release); PVT3=path/to/pvt3 for another binary, FIRST_SEED=N to
# start the seeds elsewhere than 0, and any sbatch options in SBATCH_* variables as usual.
set -euo pipefail
seeds=${1:?usage: bash bench/slurm/submit.sh SEEDS OUT [pvt3 cv options…]}
out=${2:?usage: bash bench/slurm/submit.sh SEEDS OUT [pvt3 cv options…]}
shift 2
cd "$(dirname "$0")/../.."
pvt3=${PVT3:-target/release/pvt3}
[ -x "$pvt3" ] || { echo "bench/slurm/submit.sh: no $pvt3; cargo build --release first" >&2; exit 1; }
mkdir -p "$out/slurm"
array=$(sbatch --parsable --array=0-$(( 4 * seeds - 1 )) --output="$out/slurm/%A_%a.out" \
  --export=ALL,PVT3="$pvt3",FIRST_SEED="${FIRST_SEED:-0}" bench/slurm/cv.sbatch --out "$out" "$@")
report=$(sbatch --parsable --dependency=afterany:"$array" --job-name=pvt3-report --output="$out/slurm/report.out" \
  --wrap "$pvt3 cv --report $out")
echo "array $array, report $report: tail -f $out/slurm/report.out"
