#!/usr/bin/env bash
# The small robot library's size (docs/deploy.md): built as deploy.md says, the shared library
# alone (the static one is not what a robot loads, and its link-time optimisation would double
# the work), in a target directory of its own; it must stay within 8 MiB.
#
#   bash tests/robot-small.sh check     # as tests/run.sh runs it: measure only if its inputs changed
#   bash tests/robot-small.sh measure   # build and measure now
#
# Its inputs are what decides it: the runtime's and the format's sources and manifests, the
# crates and features of the runtime's dependency tree as the lock file pins them, the build
# profiles it inherits (release, robot, robot-small: not the tests' `ci` or `robot-syms`), the
# compiler. tests/robot-small.size records the digest of those inputs and the size measured last;
# each measurement rewrites it (commit it). A crate the trainer alone uses changes none of them.
set -euo pipefail
cd "$(dirname "$0")/.."
record=tests/robot-small.size
library=target/size-check/robot-small/libpvt3_runtime.so
limit=$((8 * 1024 * 1024))

inputs() {
  {
    rustc -V
    git ls-files -z runtime/src runtime/Cargo.toml format/src format/Cargo.toml | xargs -0 sha256sum
    # The workspace's own crates print their absolute path, which differs between clones.
    cargo tree -q --locked -p pvt3-runtime --no-default-features -e normal,features --prefix none | sed "s# ($PWD/# (#" | sort -u
    awk '/^\[/ { p = /^\[profile\.(release|robot|robot-small)[].]/ } p' Cargo.toml
  } | sha256sum | cut -c1-64
}

case ${1:-check} in
  check | measure) ;;
  *) echo "usage: bash tests/robot-small.sh [check|measure]" >&2; exit 2 ;;
esac
digest=$(inputs)
if [ "${1:-check}" = check ] && grep -qx "inputs $digest" "$record" 2>/dev/null; then
  size=$(awk '$1 == "bytes" { print $2 }' "$record")
  echo "unchanged since it was measured ($record: the runtime, the format, its dependency tree, the profiles and the compiler are as they were): $size bytes (limit $limit)"
else
  RUSTFLAGS="-C llvm-args=-inline-threshold=60" CARGO_TARGET_DIR=target/size-check \
    cargo rustc -q --profile robot-small -p pvt3-runtime --no-default-features --lib --crate-type cdylib
  size=$(stat -c %s "$library")
  echo "$library: $size bytes (limit $limit)"
  printf '# The small robot library measured by tests/robot-small.sh: the digest of its inputs, its bytes.\ninputs %s\nbytes %s\n' "$digest" "$size" >"$record"
fi
if [ "$size" -gt "$limit" ]; then
  echo "tests/robot-small.sh: the small robot library has outgrown 8 MiB: see docs/deploy.md for what it holds (bench/deploy.sh sizes it by crate)" >&2
  exit 1
fi
