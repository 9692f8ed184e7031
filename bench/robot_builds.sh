#!/usr/bin/env bash
# Size against latency of the small robot build's variants (docs/deploy.md, "Size against
# latency"): each variant built as tests/robot-small.sh builds the small library (the shared
# library alone, then pvt3-run alike), its .so's bytes, and `pvt3-run --bench FILE 1 SECONDS`'s
# batch-1 median and streamed kept frame, the variants run alternately ROUNDS times so that they
# share the machine's noise. Prints a markdown table: the median over the rounds, and each
# variant's ratio to the first.
#
#   bash bench/robot_builds.sh [FILE…]     ROUNDS=3 SECONDS_EACH=2; default files: the shipped ones and a
#                                          `--robust auto` file (tests/fixtures)
#
# A variant is a name and the cargo settings (`--config`, `--features`) it adds to the
# robot-small build:
#   small     the profile as it is (opt-level 2, the inliner held back)
#   deps-s    every dependency at opt-level s, tract's kernels (tract-linalg) at 2
#   deps-s-core  the same with tract-core and ndarray at 2 too
#   rustfft   the profile as it is with the `spectral` feature: rustfft's FFT for the spectral head
#             in place of the runtime's own (src/small_fft.rs)
set -euo pipefail
cd "$(dirname "$0")/.."
rounds=${ROUNDS:-3}
seconds=${SECONDS_EACH:-2}
files=("$@")
[ ${#files[@]} -gt 0 ] || files=(shipped/icub20.onnx shipped/biotac20.onnx shipped/physiclear.onnx tests/fixtures/fabricslide-robust-auto.onnx)
pkg='profile.robot-small.package'
declare -A variants=(
  [small]=""
  [deps-s]="--config $pkg.\"*\".opt-level=\"s\" --config $pkg.tract-linalg.opt-level=2"
  [deps-s-core]="--config $pkg.\"*\".opt-level=\"s\" --config $pkg.tract-linalg.opt-level=2 --config $pkg.tract-core.opt-level=2 --config $pkg.ndarray.opt-level=2"
  [rustfft]="--features spectral"
)
order=(small deps-s deps-s-core rustfft)
for name in "${order[@]}"; do
  for what in "--lib --crate-type cdylib" "--bin pvt3-run"; do
    # shellcheck disable=SC2086 # the settings are words
    RUSTFLAGS="-C llvm-args=-inline-threshold=60" CARGO_TARGET_DIR=target/robot-builds/$name \
      cargo rustc -q --profile robot-small -p pvt3-runtime --no-default-features $what ${variants[$name]}
  done
done
out=target/robot-builds/bench.jsonl
: >"$out"
for round in $(seq "$rounds"); do
  for file in "${files[@]}"; do
    for name in "${order[@]}"; do
      target/robot-builds/$name/robot-small/pvt3-run --bench "$file" 1 "$seconds" |
        python3 -c 'import json, sys; d = json.load(sys.stdin); d["build"] = sys.argv[1]; print(json.dumps(d))' "$name" >>"$out"
    done
  done
done
python3 - "$out" "${order[@]}" <<'PY'
import json, os, statistics, sys
path, order = sys.argv[1], sys.argv[2:]
rows = [json.loads(line) for line in open(path)]
size = {b: os.path.getsize(f"target/robot-builds/{b}/robot-small/libpvt3_runtime.so") for b in order}
files = sorted({r["model"] for r in rows})
def median(build, file, key):
    return statistics.median(r.get(key, float("nan")) for r in rows if r["build"] == build and r["model"] == file)
head = "| build | `libpvt3_runtime.so` | " + " | ".join(f"{os.path.basename(f)} batch 1, µs (× small) | a kept frame, µs" for f in files) + " |"
print(head)
print("|---|---:|" + "---:|---:|" * len(files))
for b in order:
    cells = [f"{size[b]:,} B ({size[b] / size[order[0]]:.2f}×)"]
    for f in files:
        b1, base = median(b, f, "batch1_median_us"), median(order[0], f, "batch1_median_us")
        kept = median(b, f, "stream_kept_frame_median_us")
        cells.append(f"{b1:.0f} ({b1 / base:.2f}×)")
        cells.append(f"{kept:.1f}")
    print(f"| {b} | " + " | ".join(cells) + " |")
PY
