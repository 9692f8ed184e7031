#!/usr/bin/env bash
# The figures of docs/deploy.md: sizes of the robot build (`--profile robot`: fat LTO, one codegen
# unit, stripped, panics unwind) and the latency of exported models on this machine, in the pvt3
# runtime (`pvt3-run --bench`: batch 1 and 32, streamed touch) and, side by side in the same run,
# in onnxruntime (one intra-op thread). Rewrites docs/deploy.md below its figures marker.
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

cargo build -q --profile robot -p pvt3-runtime --lib --bin pvt3-run
cp target/robot/libpvt3_runtime.a target/robot/libpvt3_runtime.stripped.a
strip --strip-debug target/robot/libpvt3_runtime.stripped.a
cc runtime/examples/classify.c -O2 -I runtime/include target/robot/libpvt3_runtime.a -lm -lpthread -ldl -o target/robot/classify-static
strip target/robot/classify-static
sizes=$(mktemp)
for f in libpvt3_runtime.so libpvt3_runtime.stripped.a pvt3-run classify-static; do
  echo "$f $(stat -c %s target/robot/$f)" >> "$sizes"
done

results=$(mktemp)
for round in $(seq "$ROUNDS"); do
  for m in "${models[@]}"; do
    echo "round $round/$ROUNDS: $m" >&2
    target/robot/pvt3-run --bench "$m" 1 "$SECONDS_PER" | sed 's/^{/{"engine":"pvt3",/' >> "$results"
    "$venv/bin/python" bench/ort_latency.py "$m" "$SECONDS_PER" | sed 's/^{/{"engine":"onnxruntime",/' >> "$results"
  done
done

"$venv/bin/python" - "$sizes" "$results" "$ROUNDS" "$SECONDS_PER" <<'PY'
import json, statistics, sys, platform, re
sizes, results, rounds, seconds = sys.argv[1:]
rows = [json.loads(l) for l in open(results)]
cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), platform.processor())
med = lambda rs, k: statistics.median(r[k] for r in rs)
out = []
out.append(f"Measured by `bash bench/deploy.sh {' '.join(sorted({r['model'] for r in rows}))}` on {cpu}, "
           f"one thread, median of {rounds} rounds of about {seconds} s per measurement.\n")
out.append("| artefact (`--profile robot`) | size |\n|---|---:|")
names = {"libpvt3_runtime.so": "`libpvt3_runtime.so` (stripped)", "libpvt3_runtime.stripped.a": "`libpvt3_runtime.a` (`strip --strip-debug`)",
         "pvt3-run": "`pvt3-run` (stripped)", "classify-static": "`runtime/examples/classify.c` linked with the `.a` (stripped)"}
for line in open(sizes):
    f, n = line.split()
    out.append(f"| {names[f]} | {int(n) / 2**20:.1f} MiB |")
out.append("")
out.append("| model | kept frames | batch 1 median / p99 (µs) | batch 1, tract's kernels (µs) | batch 1, measured kernels (µs) | batch 32 (windows/s) | onnxruntime batch 1 median / p99 (µs) | onnxruntime batch 32 (windows/s) | pvt3 / onnxruntime (batch 1) |")
out.append("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
start = ["", "| model | load: read, digest check, parse (ms) | digest check alone (ms) | first call, fixed kernels (ms) | first call, measured kernels (ms) | `prepare` batch 1 and streaming (ms) | first call after `prepare` (ms) |", "|---|---:|---:|---:|---:|---:|---:|"]
stream = ["", "| model | per kept frame median / p99 (µs) | per pruned frame (µs) | end of touch median / p99 (µs) | compute per touch (µs) |", "|---|---:|---:|---:|---:|"]
for m in dict.fromkeys(r["model"] for r in rows):
    p = [r for r in rows if r["model"] == m and r["engine"] == "pvt3"]
    o = [r for r in rows if r["model"] == m and r["engine"] == "onnxruntime"]
    out.append(f"| `{m}` | {p[0]['kept_frames']} of {p[0]['frames']} | {med(p,'batch1_median_us'):.0f} / {med(p,'batch1_p99_us'):.0f} | "
               f"{med(p,'batch1_untuned_median_us'):.0f} | {med(p,'batch1_measured_median_us'):.0f} | {med(p,'batch32_windows_per_second'):.0f} | {med(o,'batch1_median_us'):.0f} / {med(o,'batch1_p99_us'):.0f} | "
               f"{med(o,'batch32_windows_per_second'):.0f} | {med(p,'batch1_median_us') / med(o,'batch1_median_us'):.2f} |")
    start.append(f"| `{m}` | {med(p,'load_ms'):.1f} | {med(p,'digest_check_ms'):.2f} | {med(p,'batch1_first_call_ms'):.0f} | {med(p,'batch1_measured_first_call_ms'):.0f} | "
                 f"{med(p,'prepare_ms'):.0f} | {med(p,'batch1_first_call_after_prepare_ms'):.2f} |")
    stream.append(f"| `{m}` | {med(p,'stream_kept_frame_median_us'):.0f} / {med(p,'stream_kept_frame_p99_us'):.0f} | "
                  f"{med(p,'stream_pruned_frame_median_us'):.2f} | {med(p,'stream_end_of_touch_median_us'):.0f} / {med(p,'stream_end_of_touch_p99_us'):.0f} | "
                  f"{med(p,'stream_compute_per_touch_us'):.0f} |")
text = "\n".join(out + start + stream) + "\n"
doc = open("docs/deploy.md").read()
marker = "<!-- figures: bash bench/deploy.sh -->\n"
open("docs/deploy.md", "w").write(doc.split(marker)[0] + marker + "\n" + text)
print(text)
PY
