#!/usr/bin/env bash
# The figures of docs/deploy.md: sizes of the two robot builds (`--profile robot`: fat LTO, one
# codegen unit, stripped, panics unwind; `--profile robot-small --no-default-features`: the same
# at opt-level 2 with the inliner held back, without threads), the small build's size by crate (from its symbols), on
# aarch64 too if the cross compiler is installed, and the latency of exported models on this
# machine, in both builds of the pvt3 runtime (`pvt3-run --bench`: batch 1 and 32, streamed
# touch) and, side by side in the same run, in onnxruntime (one intra-op thread). Rewrites
# docs/deploy.md below its figures marker.
#
#   bash bench/deploy.sh [MODEL.onnx ...]     # default: the committed iCub model (golden weights)
#   SECONDS_PER=2 ROUNDS=3 bash bench/deploy.sh runs/a.onnx runs/b.onnx
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_PER=${SECONDS_PER:-2} ROUNDS=${ROUNDS:-3}
models=("$@")
[ ${#models[@]} -gt 0 ] || models=(tests/golden/icub20/model.onnx)
venv=target/onnx-venv
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
"$venv/bin/python" -c "import onnxruntime, numpy" 2>/dev/null || "$venv/bin/pip" install -q onnxruntime numpy onnx

sizes=$(mktemp)
# What the small build needs besides its profile (Cargo.toml): LLVM's inliner held back.
small_flags="-C llvm-args=-inline-threshold=60"
for build in robot robot-small; do
  features="" flags=""
  [ "$build" = robot ] || { features=--no-default-features; flags=$small_flags; }
  echo "building $build" >&2
  RUSTFLAGS="$flags" cargo build -q --profile "$build" -p pvt3-runtime --lib --bin pvt3-run $features
  d=target/$build
  cp $d/libpvt3_runtime.a $d/libpvt3_runtime.stripped.a
  strip --strip-debug $d/libpvt3_runtime.stripped.a
  cc runtime/examples/classify.c -O2 -I runtime/include $d/libpvt3_runtime.a -lm -lpthread -ldl -o $d/classify-static
  strip $d/classify-static
  if [ "$build" = robot-small ]; then
    # The small shared library as docs/deploy.md builds it and tests/robot-small.sh holds it under
    # 8 MiB: alone (beside the static library every crate type comes out larger).
    RUSTFLAGS="$flags" cargo rustc -q --profile robot-small -p pvt3-runtime --no-default-features --lib --crate-type cdylib
  fi
  for f in libpvt3_runtime.so libpvt3_runtime.stripped.a pvt3-run classify-static; do
    echo "$build $f $(stat -c %s $d/$f)" >> "$sizes"
  done
done
# The small build with its symbols, for the size by crate.
RUSTFLAGS="$small_flags" cargo build -q --profile robot-syms -p pvt3-runtime --lib --no-default-features
symbols=$(mktemp)
nm -S --size-sort -C target/robot-syms/libpvt3_runtime.so > "$symbols"
if command -v aarch64-linux-gnu-gcc >/dev/null && rustup target list --installed | grep -qx aarch64-unknown-linux-gnu; then
  echo "building robot-small for aarch64" >&2
  CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_LINKER=aarch64-linux-gnu-gcc RUSTFLAGS="$small_flags" \
    cargo build -q --profile robot-small -p pvt3-runtime --lib --no-default-features --target aarch64-unknown-linux-gnu
  echo "robot-small-aarch64 libpvt3_runtime.so $(stat -c %s target/aarch64-unknown-linux-gnu/robot-small/libpvt3_runtime.so)" >> "$sizes"
fi

results=$(mktemp)
for round in $(seq "$ROUNDS"); do
  for m in "${models[@]}"; do
    echo "round $round/$ROUNDS: $m" >&2
    target/robot/pvt3-run --bench "$m" 1 "$SECONDS_PER" | sed 's/^{/{"engine":"pvt3",/' >> "$results"
    target/robot-small/pvt3-run --bench "$m" 1 "$SECONDS_PER" | sed 's/^{/{"engine":"pvt3-small",/' >> "$results"
    "$venv/bin/python" bench/ort_latency.py "$m" "$SECONDS_PER" | sed 's/^{/{"engine":"onnxruntime",/' >> "$results"
  done
done

"$venv/bin/python" - "$sizes" "$results" "$ROUNDS" "$SECONDS_PER" "$symbols" <<'PY'
import collections, json, statistics, sys, platform, re
sizes, results, rounds, seconds, symbols = sys.argv[1:]
rows = [json.loads(l) for l in open(results)]
cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), platform.processor())
med = lambda rs, k: statistics.median(r[k] for r in rs)
out = []
out.append(f"Measured by `bash bench/deploy.sh {' '.join(sorted({r['model'] for r in rows}))}` on {cpu}, "
           f"one thread, median of {rounds} rounds of about {seconds} s per measurement.\n")
builds = {"robot": "`robot`", "robot-small": "`robot-small`", "robot-small-aarch64": "`robot-small`, aarch64"}
names = {"libpvt3_runtime.so": "`libpvt3_runtime.so` (stripped)", "libpvt3_runtime.stripped.a": "`libpvt3_runtime.a` (`strip --strip-debug`)",
         "pvt3-run": "`pvt3-run` (stripped)", "classify-static": "`runtime/examples/classify.c` linked with the `.a` (stripped)"}
size = collections.defaultdict(dict)
for line in open(sizes):
    b, f, n = line.split()
    size[names[f]][b] = f"{int(n) / 2**20:.1f} MiB"
present = [b for b in builds if any(b in v for v in size.values())]
out.append("| artefact | " + " | ".join(builds[b] for b in present) + " |\n|---|" + "---:|" * len(present))
for name, by in size.items():
    out.append(f"| {name} | " + " | ".join(by.get(b, "") for b in present) + " |")
# Symbols by the crate that names them (a generic counts for the crate that defines it, whoever
# instantiates it); what no symbol covers is tables, unwinding data and relocations.
by_crate, total = collections.Counter(), 0
for line in open(symbols):
    parts = line.split(None, 3)
    if len(parts) < 4:
        continue
    n = int(parts[1], 16)
    total += n
    m = re.match(r"[<&]*(?:dyn )?([a-z_][a-z0-9_]*)::", parts[3])
    by_crate[m.group(1) if m else "other (assembly kernels, unnamed)"] += n
out.append("")
out.append("Size by crate of the small build (x86-64, `--profile robot-syms`: the same build with its symbols; `nm -S`):\n")
out.append("| crate | size |\n|---|---:|")
for crate, n in by_crate.most_common(12):
    out.append(f"| `{crate}` | {n / 2**20:.2f} MiB |")
rest = total - sum(n for _, n in by_crate.most_common(12))
out.append(f"| {len(by_crate) - 12} other crates | {rest / 2**20:.2f} MiB |")
out.append(f"| all symbols | {total / 2**20:.2f} MiB |")
out.append("")
out.append("| model | kept frames | batch 1 median / p99 (µs) | batch 1, small build (µs) | batch 1, tract's kernels (µs) | batch 1, measured kernels (µs) | batch 32 (windows/s) | onnxruntime batch 1 median / p99 (µs) | onnxruntime batch 32 (windows/s) | pvt3 / onnxruntime (batch 1) |")
out.append("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
start = ["", "| model | load: read, digest check, parse (ms) | digest check alone (ms) | first call, fixed kernels (ms) | first call, measured kernels (ms) | `prepare` batch 1 and streaming (ms) | first call after `prepare` (ms) |", "|---|---:|---:|---:|---:|---:|---:|"]
stream = ["", "| model | per kept frame median / p99 (µs) | per pruned frame (µs) | end of touch median / p99 (µs) | compute per touch (µs) |", "|---|---:|---:|---:|---:|"]
slide = ["", "| model | continuous, one answer median (µs) | continuous, per token answering after every token (µs) | batch 1 median (µs) |", "|---|---:|---:|---:|"]
for m in dict.fromkeys(r["model"] for r in rows):
    p = [r for r in rows if r["model"] == m and r["engine"] == "pvt3"]
    o = [r for r in rows if r["model"] == m and r["engine"] == "onnxruntime"]
    q = [r for r in rows if r["model"] == m and r["engine"] == "pvt3-small"]
    out.append(f"| `{m}` | {p[0]['kept_frames']} of {p[0]['frames']} | {med(p,'batch1_median_us'):.0f} / {med(p,'batch1_p99_us'):.0f} | "
               f"{med(q,'batch1_median_us'):.0f} | {med(p,'batch1_untuned_median_us'):.0f} | {med(p,'batch1_measured_median_us'):.0f} | {med(p,'batch32_windows_per_second'):.0f} | {med(o,'batch1_median_us'):.0f} / {med(o,'batch1_p99_us'):.0f} | "
               f"{med(o,'batch32_windows_per_second'):.0f} | {med(p,'batch1_median_us') / med(o,'batch1_median_us'):.2f} |")
    start.append(f"| `{m}` | {med(p,'load_ms'):.1f} | {med(p,'digest_check_ms'):.2f} | {med(p,'batch1_first_call_ms'):.0f} | {med(p,'batch1_measured_first_call_ms'):.0f} | "
                 f"{med(p,'prepare_ms'):.0f} | {med(p,'batch1_first_call_after_prepare_ms'):.2f} |")
    slide.append(f"| `{m}` | {med(p,'continuous_answer_median_us'):.0f} | {med(p,'continuous_per_token_us'):.0f} | {med(p,'batch1_median_us'):.0f} |")
    if "stream_kept_frame_median_us" not in p[0]:
        stream.append(f"| `{m}` | not streamed: a spectral head reads the whole window | | | |")
        continue
    stream.append(f"| `{m}` | {med(p,'stream_kept_frame_median_us'):.0f} / {med(p,'stream_kept_frame_p99_us'):.0f} | "
                  f"{med(p,'stream_pruned_frame_median_us'):.2f} | {med(p,'stream_end_of_touch_median_us'):.0f} / {med(p,'stream_end_of_touch_p99_us'):.0f} | "
                  f"{med(p,'stream_compute_per_touch_us'):.0f} |")
text = "\n".join(out + start + stream + slide) + "\n"
doc = open("docs/deploy.md").read()
marker = "<!-- figures: bash bench/deploy.sh -->\n"
open("docs/deploy.md", "w").write(doc.split(marker)[0] + marker + "\n" + text)
print(text)
PY
