#!/usr/bin/env bash
# The hostile-files test (runtime/tests/hostile_files.rs) at length: CASES re-signed damaged copies
# of every kind of file pvt3 writes (the golden iCub model, the shipped iCub, BioTac and camera
# files, a `--robust auto` file; a camera's 8-bit frames of the wrong length pushed into each
# camera file that runs) and as many damaged .npy inputs of each kind (float32 windows, a camera's
# 8-bit touch), on two threads; prints what was refused, what ran and what panicked, by kind of
# damage. The test fails on any panic, caught or not, and on any refusal that names no part of the
# file (an initializer, a node or its tensor, the graph's input, a header entry).
# docs/benchmarks.md gives its figures.
#
#   bash bench/fuzz.sh [CASES [FILE]]   # default 100000 per file; FILE: only the files whose path holds it
set -euo pipefail
cd "$(dirname "$0")/.."
PVT3_FUZZ_CASES=${1:-100000} PVT3_FUZZ_FILE=${2:-} cargo test -q --release -p pvt3-runtime --test hostile_files -- --nocapture --test-threads 1
