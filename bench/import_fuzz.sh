#!/usr/bin/env bash
# The import fuzz (tests/import_fuzz.rs) at length: MUTANTS hostile recordings (damaged files,
# names and options over CSV trees, frame folders, still images and videos), each imported by the
# release build with a time limit; prints the outcomes by tree, damage and outcome. It fails on any
# panic, signal, timeout, garbage or refusal that names neither a file nor an option. Built in the
# tests' profile (`ci`), so that it reuses their build.
# docs/benchmarks.md gives its figures. PVT3_IMPORT_FUZZ_BIN=path/to/pvt3 runs it against another
# build.
#
#   bash bench/import_fuzz.sh [MUTANTS]        # default 10000
set -euo pipefail
cd "$(dirname "$0")/.."
PVT3_IMPORT_FUZZ=${1:-10000} cargo test -q --profile ci -p pvt3-trainer --test import_fuzz -- --nocapture
