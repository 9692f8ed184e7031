#!/usr/bin/env bash
# The tests, exactly as CI runs them (.ci/run):
#   0. what they need, installed in the background beside step 1's build (rustup's musl, Windows
#      and macOS targets and clippy; Debian's librsvg2-bin for the picture tests, ffmpeg for the
#      camera import's videos, valgrind for the C ABI, pkgconf for the installed library's flags,
#      gcc-aarch64-linux-gnu, libc6-dev-arm64-cross, musl-dev:arm64 and qemu-user,
#      gcc-mingw-w64-x86-64, clang and musl-tools, with apt-get as root), or it says exactly what
#      is missing;
#   1. the whole workspace on this machine (cargo test --profile ci --workspace: the release
#      build with tract-core unoptimised and the runtime at opt-level 1, Cargo.toml's `ci`);
#   2. the C ABI under valgrind (x86-64): every entry point's error paths and the C example's
#      paths (beside step 3's tests under qemu), no invalid read or write, no leak;
#   3. the robot runtime cross-built for aarch64 (64-bit ARM: Jetson Orin, Raspberry Pi 4/5) as
#      static musl binaries, and its tests that show it computes what x86-64 does run under
#      qemu: golden logits, bit-identical loads, the kernels, damaged files, streaming, every
#      C-ABI error path, the Rust example built, and runtime/examples/classify.c built with
#      aarch64-linux-gnu-gcc (given musl's arm64 headers and libraries) and run, and the ROS
#      node's answers through a zenoh peer on the host; then the pvt3-run and pvt3-ros those
#      tests built are checked static, pvt3-run held to the host build's answers on the golden
#      windows. What needs onnxruntime or candle stays on the host. It is built without
#      default features, as the small robot build is (no `threads`, no rayon, no `spectral`:
#      docs/deploy.md), so both supported feature sets are tested: all of them on the host, the
#      small one on aarch64. musl or glibc changes one line of the runtime (runtime/src/heap.rs,
#      glibc's allocator tuning, tested on the host);
#   4. other platforms: the trainer checked (cargo check) for macOS (aarch64-apple-darwin, without
#      its `bags` feature, whose C needs the macOS SDK; its
#      assembly by clang), and every crate's library and programs for Windows
#      (x86_64-pc-windows-gnu, with Debian's mingw-w64) with clippy's lints, warnings denied; the
#      runtime's and the format's tests linted there too (every unsafe block has a SAFETY note);
#      the runtime, pvt3-run and pvt3-ros built as static musl binaries for x86-64, pvt3-run run
#      on the golden windows and held to the host build's answers. In the
#      background from the end of step 1's build, in a target directory of its own (so that
#      neither cargo waits for the other's lock): it takes the CPU the other steps leave;
#   5. the small robot library's size (tests/robot-small.sh, in the background from the start):
#      built as docs/deploy.md says whenever the runtime, the format, its dependency tree, the
#      build profiles or the compiler changed since it was last measured (tests/robot-small.size),
#      it must stay within 8 MiB.
# Each step's heading gives its start in seconds and how busy the cores were since the last
# heading; times under qemu mean nothing, outputs do.
set -euo pipefail
cd "$(dirname "$0")/.."

# Each step's heading says when it starts, in seconds since the script did (the steps' times),
# and how busy the machine's cores were since the previous heading (/proc/stat: on two cores,
# 100 % is both busy; where it is low, a step waits on one thread and could share the machine).
# The machine's busy and total CPU ticks so far (user, nice, system, irq, softirq; and idle, iowait).
cpu_ticks() { awk '/^cpu / { print $2 + $3 + $4 + $7 + $8, $2 + $3 + $4 + $5 + $6 + $7 + $8; exit }' /proc/stat 2>/dev/null || echo 0 0; }
# How busy the cores were between `since` (ticks as cpu_ticks gives them) and now, as `, cores N % busy`.
busy() {
  local now
  now=($(cpu_ticks))
  [ "${now[1]}" = "$2" ] || printf ', cores %d %% busy' $(((now[0] - $1) * 100 / (now[1] - $2)))
}
first_ticks=($(cpu_ticks))
heading_ticks=("${first_ticks[@]}")
step() {
  local since
  since=$(busy "${heading_ticks[@]}")
  heading_ticks=($(cpu_ticks))
  printf '\n== [%d s%s] %s\n' "$SECONDS" "${since:+$since since the last heading}" "$*"
}
missing() { echo "tests/run.sh: missing $1" >&2; exit 1; }
# Installs the Debian packages named (apt-get, as root), or says exactly what is missing.
install_debian() {
  [ $# -gt 0 ] || return 0
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
    echo "installing $*"
    # A package of another architecture (musl-dev:arm64) needs that architecture known to dpkg.
    if [[ " $* " == *:arm64\ * ]] && ! dpkg --print-foreign-architectures | grep -qx arm64; then
      dpkg --add-architecture arm64
    fi
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "$@" >/dev/null
  else
    missing "the Debian packages $*: as root, apt-get install $*"
  fi
}
# Every test run's output goes here too, for the summary at the end.
log=$(mktemp)
# The steps run in the background, killed if the script stops early.
background=()
trap 'kill ${background[@]+"${background[@]}"} 2>/dev/null || true; rm -f "$log"' EXIT
# Waits for a background step started above, prints its output, and stops with `failed` if it failed.
joined() {
  local pid=$1 output=$2 failed=$3 status=0
  wait "$pid" || status=$?
  cat "$output"
  [ "$status" = 0 ] || { echo "tests/run.sh: $failed" >&2; exit 1; }
}
cargo_test() { cargo test "$@" 2>&1 | tee -a "$log"; }

# The runtime's x86-64 kernels are tested for every instruction set they are written for, and a
# test fails on a machine that lacks one it was asked to cover (it never passes by checking
# nothing). Machines differ: cover the sets this one has, and say which were left out.
if [ "$(uname -m)" = x86_64 ] && [ -z "${PVT3_TEST_ISAS:-}" ]; then
  isas=()
  grep -qw avx512f /proc/cpuinfo && isas+=(avx512)
  grep -qw avx2 /proc/cpuinfo && grep -qw fma /proc/cpuinfo && isas+=(avx2)
  [ ${#isas[@]} -gt 0 ] || missing "a CPU with AVX2 and FMA: the runtime's kernel tests need one"
  PVT3_TEST_ISAS=$(IFS=,; echo "${isas[*]}")
  export PVT3_TEST_ISAS
  [[ $PVT3_TEST_ISAS == *avx512* ]] || echo "note: this machine has no AVX-512, so the runtime's AVX-512 kernels are not tested here (PVT3_TEST_ISAS=$PVT3_TEST_ISAS)"
fi

# The small robot library's size (tests/robot-small.sh), in the background from the start: when
# what decides it changed, it is built, and its single-threaded phases (one codegen unit, fat
# LTO) then overlap the other steps; otherwise its record is read. Checked at the end.
mkdir -p target
# A fresh target directory grows to 4.9 GiB (a fresh clone of cb76bbc: the host build 2.7, the other
# platforms 1.2, aarch64 0.75, the onnxruntime venv 0.2), and a disk that fills mid-build stops the
# run minutes in with "No space left on device": say so before anything is built.
if [ ! -d target/ci ]; then
  free_mib=$(( $(df -Pk target | awk 'NR == 2 { print $4 }') / 1024 ))
  [ "$free_mib" -ge 6144 ] || missing "disk space: a fresh run of the tests writes 4.9 GiB under target/ and needs 6 GiB free there (with room for Debian's packages); $free_mib MiB are free"
fi
small_log=target/robot-small-size.log
bash tests/robot-small.sh check >"$small_log" 2>&1 &
small_pid=$!
background+=("$small_pid")

# Step 0: what the tests need, installed in the background while the host build compiles (the
# host build needs none of it: it spends CPU while apt-get and rustup mostly wait on the network).
what_the_tests_need() {
  local need=()
  # The picture tests render the SVG files they draw with librsvg and look at the pixels; on
  # x86-64 the C ABI and the C example run under valgrind too (runtime/tests/c_abi.rs, PVT3_VALGRIND).
  command -v rsvg-convert >/dev/null || need+=(librsvg2-bin)
  # The C example is built with the flags pkg-config reads from the installed pvt3.pc.
  command -v pkg-config >/dev/null || need+=(pkgconf)
  [ "$(uname -m)" != x86_64 ] || command -v valgrind >/dev/null || need+=(valgrind)
  # The camera import's tests write videos with FFmpeg and decode them with it.
  command -v ffmpeg >/dev/null && command -v ffprobe >/dev/null || need+=(ffmpeg)
  # aarch64: the cross compiler and the arm64 C library it expects beside it, musl's arm64
  # headers and static libraries (the tests and the C example are static musl binaries), qemu.
  command -v aarch64-linux-gnu-gcc >/dev/null || need+=(gcc-aarch64-linux-gnu)
  [ -e /usr/aarch64-linux-gnu/lib/crt1.o ] || need+=(libc6-dev-arm64-cross)
  [ -e /usr/lib/aarch64-linux-musl/libc.a ] || need+=(musl-dev:arm64)
  command -v qemu-aarch64 >/dev/null || need+=(qemu-user)
  # Other platforms: build scripts' C and assembly for Windows; for macOS, a build script's
  # assembly (psm) takes clang's -arch; tract's x86-64 assembly kernels, built for musl (whose
  # musl-gcc specs file, retargeted, also builds the C example for aarch64).
  command -v x86_64-w64-mingw32-gcc >/dev/null || need+=(gcc-mingw-w64-x86-64)
  command -v clang >/dev/null || need+=(clang)
  command -v musl-gcc >/dev/null || need+=(musl-tools)
  install_debian ${need[@]+"${need[@]}"}
  cargo clippy --version >/dev/null 2>&1 || rustup component add clippy || missing "clippy (rustup component add clippy)"
  local t
  for t in "$target" x86_64-pc-windows-gnu aarch64-apple-darwin x86_64-unknown-linux-musl; do
    rustup target list --installed | grep -qx "$t" || rustup target add "$t" || missing "the Rust target $t (rustup target add $t)"
  done
}
target=aarch64-unknown-linux-musl
step "what the tests need: Debian's packages and rustup's targets (in the background, beside the host build)"
need_log=target/what-the-tests-need.log
(set -e; what_the_tests_need) >"$need_log" 2>&1 &
need_pid=$!
background+=("$need_pid")

# A static binary of pvt3-run (run through the emulator named after it, if any) answers the
# golden windows, the shipped BioTac touch (its spectral head's transform, the small build's own
# FFT), the shipped camera touch (a head over the image's space, with the pixels) and a file the
# default `--robust auto` trained (its spectral head of 16 bands: `pvt3 import
# FabricSlide/data/fabric --name '{class}_F{force}_V{speed}mmps_*' --out fabric.npz`, `pvt3
# --threads 1 train --data fabric.npz --out run --epochs 3 --export robust-auto.onnx`; its
# touch the first 141 frames of the set's first) as the host build does, within the 1e-5 every
# form of the model keeps to the golden logits (the camera touch, 66 M multiply-adds, sums in
# another order on aarch64: 1.4e-6 off) (target/CASE-host.jsonl, written after the host build).
is_static() {
  if readelf -l "$1" | grep -q INTERP; then
    echo "tests/run.sh: $1 asks for a dynamic loader: not a static binary" >&2
    return 1
  fi
}
same_as_host() {
  local bin=$1 name=$(basename "$(dirname "$(dirname "$1")")") compared=()
  shift
  is_static "$bin"
  for case in "${!answered[@]}"; do
    "$@" "$bin" --json ${answered[$case]} >target/$case-$name.jsonl
    compared+=(target/$case-$name.jsonl target/$case-host.jsonl)
  done
  python3 - "${compared[@]}" <<'EOF'
import json, sys
for built, host_path in zip(sys.argv[1::2], sys.argv[2::2]):
    static, host = ([json.loads(line) for line in open(path)] for path in (built, host_path))
    assert len(static) == len(host) >= 1, (built, len(static), len(host))
    worst = max(abs(a - b) for s, h in zip(static, host) for a, b in zip(s["probabilities"], h["probabilities"]))
    assert worst <= 1e-5 and all(s["class"] == h["class"] for s, h in zip(static, host)), (built, worst)
    print(f"{built}: {len(static)} windows' probabilities within {worst:.1e} of the host build's, every class the same")
EOF
}
# Each case: the model and its input.
declare -A answered=(
  [golden]="tests/golden/icub20/model.onnx tests/golden/icub20/input.npy"
  [spectral]="shipped/biotac20.onnx shipped/biotac20-touch.npy"
  [camera]="shipped/physiclear.onnx shipped/physiclear-touch.npy"
  [robust]="tests/fixtures/fabricslide-robust-auto.onnx tests/fixtures/fabricslide-touch.npy"
)

# Step 4, run in the background once the host build is done (see the top), in one target
# directory and one profile, so that the build scripts and procedural macros, built for this
# machine, are built once for all three: `dev` without debug information, debug assertions,
# overflow checks or incremental caches; tract's kernels crate optimised (opt-level 1), which
# unoptimised answers wrongly on aarch64 (the golden windows' probabilities 0.039 off the host's
# under qemu, with or without debug assertions; at opt-level 1 within 3e-8, as the optimised
# builds are).
other_platforms() {
  local platforms=(--target-dir target/platforms) dev=(debug=false debug-assertions=false overflow-checks=false incremental=false 'package.tract-linalg.opt-level=1')
  platforms+=($(printf -- "--config profile.dev.%s " "${dev[@]}"))
  # The trainer checked for macOS; every crate's library and programs, the trainer's among them,
  # checked for Windows with clippy's lints, warnings denied (the trainer's tests use Unix's
  # signals and byte paths, so they are linted on the host alone, by whoever changes them).
  # For macOS without its `bags` feature: the bag storages' C (SQLite, zstd, lz4) needs the
  # macOS SDK's headers, which this machine lacks (Windows's, mingw's, it has).
  CC_aarch64_apple_darwin=clang cargo check "${platforms[@]}" --target aarch64-apple-darwin -p pvt3-trainer --bins --no-default-features
  cargo clippy "${platforms[@]}" --target x86_64-pc-windows-gnu --workspace --lib --bins -- -D warnings
  # The runtime's lints: clippy with warnings denied (every unsafe block has a SAFETY note), on
  # the Windows build the check above has half done (the same code as Linux's but for glibc's
  # allocator tuning in runtime/src/heap.rs, which only the host build compiles, and which is
  # therefore neither linted nor built with warnings denied; the host's tests run it).
  cargo clippy "${platforms[@]}" --target x86_64-pc-windows-gnu -p pvt3-runtime -p pvt3-format --all-targets -- -D warnings
  # Their API docs: every public item documented (`#![warn(missing_docs)]`), every link resolved.
  RUSTDOCFLAGS="-D warnings" cargo doc "${platforms[@]}" --no-deps -p pvt3-runtime -p pvt3-format
  # The runtime, pvt3-run and the ROS node built to show that they link statically and compute
  # what the host build computes, never timed: as the small robot build (docs/deploy.md) without
  # default features (one thread a plan, its own FFT: a static robot binary is a small one). The
  # aarch64 ones are the aarch64 tests' own build (step 3), where the node's tests run too.
  cargo build "${platforms[@]}" --target x86_64-unknown-linux-musl -p pvt3-runtime -p pvt3-ros --no-default-features --lib --bin pvt3-run --bin pvt3-ros
  same_as_host target/platforms/x86_64-unknown-linux-musl/debug/pvt3-run
  is_static target/platforms/x86_64-unknown-linux-musl/debug/pvt3-ros
  target/platforms/x86_64-unknown-linux-musl/debug/pvt3-ros --help | grep -q "touch_status"
  # Every crate packs as `cargo publish` would pack it: its metadata, its files, its internal
  # dependencies by version (the packages made earlier in the run stand in for crates.io). Not
  # built again from the packages (--no-verify): that would build the workspace a third time.
  cargo package --target-dir target/platforms --workspace --no-verify
}

step "host: cargo test --profile ci --workspace (built, then run)"
cargo test --profile ci --workspace --no-run
for case in "${!answered[@]}"; do
  target/ci/pvt3-run --json ${answered[$case]} >target/$case-host.jsonl
done

step "what the tests need (installed beside the host build)"
joined "$need_pid" "$need_log" "what the tests need could not be installed"
# On x86-64 the C example's test runs beside the tests under qemu, its example under valgrind.
valgrind=()
[ "$(uname -m)" != x86_64 ] || valgrind=(--skip the_c_example_gives_the_rust_result)

step "other platforms, in the background: the trainer checked for macOS, every crate linted for Windows, the runtime, pvt3-run and pvt3-ros built static with musl for x86-64"
platforms_log=target/other-platforms.log
(set -e; other_platforms) >"$platforms_log" 2>&1 &
platforms_pid=$!
background+=("$platforms_pid")
echo "(its output follows the aarch64 tests)"

step "host: the tests"
cargo_test --profile ci --workspace -- ${valgrind[@]+"${valgrind[@]}"}

step "aarch64: cargo test --profile ci --target $target -p pvt3-runtime -p pvt3-format -p pvt3-ros --no-default-features --no-run"
# The aarch64 build's compiler, linker and runner (tests/aarch64-env.sh), for its build and its
# tests alone (subshells): the other platforms' builds name their own.
aarch64_tests=(--profile ci --target "$target" -p pvt3-runtime -p pvt3-format -p pvt3-ros --no-default-features)
(source tests/aarch64-env.sh && cargo test "${aarch64_tests[@]}" --no-run)

valgrind_pid=
if [ ${#valgrind[@]} -gt 0 ]; then
  step "C ABI under valgrind: every entry point's error paths and the C example's, no invalid access, no leak (in the background, beside the tests under qemu)"
  # The test binary the host step built (the same command, so nothing is built again: with
  # `-p pvt3-runtime` alone its dependencies' features differ, and tract would be rebuilt).
  c_abi=$(cargo test -q --profile ci --workspace --no-run --message-format=json 2>/dev/null |
    python3 -c 'import json, sys
for line in sys.stdin:
    m = json.loads(line)
    if m.get("reason") == "compiler-artifact" and m["target"]["name"] == "c_abi" and m.get("executable"):
        print(m["executable"])')
  # One thread for about two minutes, beside the tests under qemu, which leave a core idle for
  # much of theirs (a few long tests each run alone at the end of their harness): the entry points
  # under valgrind, then the C example's test, which builds the example, holds its answers to the
  # runtime's and runs it under valgrind (PVT3_VALGRIND) on its way through and its error paths.
  valgrind_log=target/valgrind.log
  (valgrind -q --error-exitcode=99 --leak-check=full --errors-for-leak-kinds=definite,indirect --show-leak-kinds=definite,indirect \
    "$c_abi" --test-threads 1 every_entry_point_reports_instead_of_crashing 2>&1 | tee -a "$log"
    PVT3_VALGRIND=1 "$c_abi" the_c_example_gives_the_rust_result 2>&1 | tee -a "$log") >"$valgrind_log" &
  valgrind_pid=$!
  background+=("$valgrind_pid")
  echo "(its output follows the aarch64 tests)"
fi

step "aarch64: the tests under qemu"
# Under the emulator runs what shows that the ARM build computes what x86-64 computes: the golden
# logits with every kernel choice, bit-identical answers across loads (two loads there, three on
# the host), the kernels, streaming, the readers, the C example (which streams, peeks at and
# slides over two of the golden windows there, all eight on the host, and holds each to the batch
# answer; so `stream`'s own eight-window equality runs on the host alone). Left to the host, where
# they run in seconds rather than minutes under qemu: a benchmark (under an emulator it measures
# nothing; its report's form is tested on the host), and tests of logic and robustness that no
# arithmetic of the target changes: the continuous stream's answer at every frame and its reset,
# the Rust example's 79 answers (built for aarch64 above; its arithmetic is the golden tests'),
# pvt3-run's JSON lines (its answers stay), one classifier shared by four threads, the thousands
# of hostile files (damaged_files stays), and a provisional answer's logic: a peek after each of
# 75 frames (150 runs of the temporal plan, 40 s under qemu; peeks run there in the C example
# and the C ABI's test) and a file without the key bias streaming but refusing to peek. The ROS
# node's tests run there, the node under qemu and its peer on the host: a taxel array's touches
# and a camera's recording over its moving span answered as the runtime answers them; the
# hostile traffic, logic alone, runs on the host.
qemu_skips=(bench_reports_batch_and_streaming_latencies every_answer_is_the_batch_classification_of_the_latest_window
  a_peek_reads_the_touch_so_far_and_leaves_it_going a_file_without_the_key_bias_gives_no_provisional_answer
  a_reset_stream_waits_for_a_whole_window_and_misuse_is_an_error streaming_frame_by_frame_equals_the_whole_window
  the_example_answers_as_the_runtime_does json_gives_every_probability_of_every_window
  a_classifier_shared_by_threads_answers_each_as_it_answers_one
  re_signed_damaged_models_are_refused_by_name_or_run_and_never_panic damaged_npy_inputs_are_refused_and_never_panic
  a_camera_s_touches_are_answered_as_the_runtime_answers_them_through_hostile_traffic)
(source tests/aarch64-env.sh && cargo_test "${aarch64_tests[@]}" -- $(printf -- '--skip %s ' "${qemu_skips[@]}"))

if [ -n "$valgrind_pid" ]; then
  step "C ABI under valgrind (run beside the tests under qemu)"
  joined "$valgrind_pid" "$valgrind_log" "the C ABI failed under valgrind"
fi

step "aarch64: pvt3-run and pvt3-ros, as the tests built them, are static; pvt3-run answers the golden windows as the host build does"
same_as_host "target/$target/ci/pvt3-run" qemu-aarch64
is_static "target/$target/ci/pvt3-ros"

step "other platforms (run beside the steps above)"
joined "$platforms_pid" "$platforms_log" "another platform's build failed"

step "the small robot library: at most 8 MiB (docs/deploy.md)"
joined "$small_pid" "$small_log" "the small robot library's size check failed (bash tests/robot-small.sh measure)"

# One closing line for all harnesses, host and aarch64 (cargo's own runs end with doc-test
# harnesses that hold no test).
echo "(all steps: $SECONDS s$(busy "${first_ticks[@]}"))"
grep '^test result:' "$log" | awk '{ p += $4; f += $6 } END { printf "\ntests: %d passed, %d failed\n", p, f }'
