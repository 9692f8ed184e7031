#!/usr/bin/env bash
# The hostile-files test (runtime/tests/hostile_files.rs) at length: CASES re-signed damaged copies
# of each real model (the golden iCub model, a BioTac model with a spectral head) and as many
# damaged .npy inputs, on two threads; prints what was refused, what ran and what panicked, by
# kind of damage. The test fails on any panic, caught or not. docs/deploy.md gives its figures.
#
#   bash bench/fuzz.sh [CASES]        # default 100000 per file
set -euo pipefail
cd "$(dirname "$0")/.."
PVT3_FUZZ_CASES=${1:-100000} cargo test -q --release -p pvt3-runtime --test hostile_files -- --nocapture --test-threads 1
