#!/usr/bin/env bash
# Installs the runtime's C library where a robot's build finds it: PREFIX/lib/libpvt3_runtime.a
# and .so, PREFIX/include/pvt3.h and PREFIX/lib/pkgconfig/pvt3.pc and pvt3-static.pc, so that
# `pkg-config --cflags --libs pvt3` gives the flags of the shared library (the static one where
# no shared one is built, as for musl), and `pvt3-static` those of the static library, by its
# path: with both installed, `-lpvt3_runtime` would take the shared one.
#
#   bash runtime/install.sh PREFIX [PROFILE]   # builds it first: cargo build --profile PROFILE
#                                              # (default robot; robot-small: see docs/deploy.md)
#   PVT3_LIB_DIR=DIR bash runtime/install.sh PREFIX   # installs the libraries already built in DIR
#
# Cross-building for the robot: CARGO_BUILD_TARGET=aarch64-unknown-linux-gnu (docs/deploy.md).
set -euo pipefail
cd "$(dirname "$0")/.."
prefix=${1:?usage: bash runtime/install.sh PREFIX [PROFILE]}
profile=${2:-robot}
if [ -z "${PVT3_LIB_DIR:-}" ]; then
  cargo build -q --profile "$profile" -p pvt3-runtime
  PVT3_LIB_DIR=target/${CARGO_BUILD_TARGET:+$CARGO_BUILD_TARGET/}$profile
fi
libs=()
for lib in libpvt3_runtime.a libpvt3_runtime.so; do
  [ ! -e "$PVT3_LIB_DIR/$lib" ] || libs+=("$PVT3_LIB_DIR/$lib")
done
[ ${#libs[@]} -gt 0 ] || { echo "runtime/install.sh: no libpvt3_runtime.a or .so in $PVT3_LIB_DIR" >&2; exit 1; }
prefix=$(mkdir -p "$prefix" && cd "$prefix" && pwd)
version=$(awk -F'"' '/^version *=/ { print $2; exit }' Cargo.toml)
install -d "$prefix/lib/pkgconfig" "$prefix/include"
install -m 644 "${libs[@]}" "$prefix/lib/"
install -m 644 runtime/include/pvt3.h "$prefix/include/"
pcs=(pvt3)
[ ! -e "$prefix/lib/libpvt3_runtime.a" ] || pcs+=(pvt3-static)
for pc in "${pcs[@]}"; do
  sed -e "s#@PREFIX@#$prefix#" -e "s#@VERSION@#$version#" "runtime/pkg/$pc.pc.in" >"$prefix/lib/pkgconfig/$pc.pc"
done
echo "installed pvt3 $version into $prefix: lib/$(cd "$prefix/lib" && ls libpvt3_runtime.* | paste -sd,), include/pvt3.h, lib/pkgconfig/$(printf '%s.pc\n' "${pcs[@]}" | paste -sd,)"
