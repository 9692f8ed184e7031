# Sourced (by tests/run.sh and bench/ros_node.sh) before a cargo command for
# aarch64-unknown-linux-musl, from the workspace's root: its compiler, linker and runner. Static
# musl binaries, so the emulator needs no arm64 loader: Rust's links with musl's own start files
# and C library (rustup's target); the C example (and tract's assembly) with aarch64-linux-gnu-gcc
# given musl's arm64 headers and libraries (Debian's musl-dev:arm64) by the specs file Debian's
# musl-gcc gives gcc on x86-64, retargeted, and unwinding with the unwinder Rust's musl target
# ships (gcc's, built for glibc, asks for glibc's _dl_find_object). (rustc warns that a static musl
# target builds no shared library: the static one and the Rust library are what the tests use.)
aarch64_cc=$PWD/target/aarch64-linux-musl-gcc
mkdir -p target
sed -e 's/x86_64/aarch64/g' -e "s|%:if-exists(libgcc_eh.a%s)|$(rustc --print sysroot)/lib/rustlib/aarch64-unknown-linux-musl/lib/self-contained/libunwind.a|" \
  /usr/lib/x86_64-linux-musl/musl-gcc.specs >"$aarch64_cc.specs"
printf '#!/bin/sh\nexec aarch64-linux-gnu-gcc "$@" -specs "%s" -static\n' "$aarch64_cc.specs" >"$aarch64_cc"
chmod +x "$aarch64_cc"
export TARGET_CC=$aarch64_cc
export CARGO_TARGET_AARCH64_UNKNOWN_LINUX_MUSL_LINKER=aarch64-linux-gnu-gcc
export CARGO_TARGET_AARCH64_UNKNOWN_LINUX_MUSL_RUNNER=qemu-aarch64
# The tests run the C example, pvt3-run and pvt3-ros through the same emulator.
export PVT3_TARGET_RUNNER=qemu-aarch64
# Code compiled only off x86-64 gets no clippy: at least no warning may pass here.
export CARGO_TARGET_AARCH64_UNKNOWN_LINUX_MUSL_RUSTFLAGS="-D warnings"
