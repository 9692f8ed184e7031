#!/usr/bin/env bash
# The soak test of docs/deploy.md: one classifier shared by several threads for minutes (batches,
# sessions with provisional answers after every token, continuous streams), every answer checked
# against one thread's, resident memory sampled. Not in CI (it runs for minutes by design).
#
#   bash bench/soak.sh [THREADS] [SECONDS] [MODEL.onnx INPUT.npy]   # default: 4 threads, 600 s, the golden iCub model
set -euo pipefail
cd "$(dirname "$0")/.."
threads=${1:-4} seconds=${2:-600}
model=${3:-tests/golden/icub20/model.onnx} input=${4:-tests/golden/icub20/input.npy}
cargo build -q --release -p pvt3-bench-tools --bin soak
target/release/soak "$model" "$input" "$threads" "$seconds"
