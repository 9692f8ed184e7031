#!/usr/bin/env bash
# One model against its pruned child, side by side: `pvt3-run --bench` at one thread on each,
# alternately, ROUNDS times, so that both see the same machine; prints a markdown table of the
# medians over the rounds and the pruned model's share of the other's time.
#
#   bash bench/pruned_latency.sh UNPRUNED.onnx PRUNED.onnx [ROUNDS (3)] [SECONDS (2)]
#
# PVT3_RUN names the binary (default target/release/pvt3-run).
set -euo pipefail
[ $# -ge 2 ] || { sed -n 2,8p "$0"; exit 2; }
run=${PVT3_RUN:-target/release/pvt3-run}
rounds=${3:-3}
seconds=${4:-2}
out=$(mktemp)
for r in $(seq "$rounds"); do
  for model in "$1" "$2"; do
    "$run" --bench "$model" 1 "$seconds" >>"$out"
  done
done
python3 - "$out" "$1" "$2" <<'PY'
import json, statistics, sys
rows = [json.loads(line) for line in open(sys.argv[1])]
models = sys.argv[2:]
fields = [("stream_kept_frame_median_us", "a streamed frame, median (µs)"),
          ("stream_kept_frame_p99_us", "a streamed frame, p99 (µs)"),
          ("stream_end_of_touch_median_us", "the end of a touch, median (µs)"),
          ("batch1_median_us", "a whole window at once, median (µs)")]
median = {m: {k: statistics.median(r[k] for r in rows if r["model"] == m) for k, _ in fields} for m in models}
print(f"| one thread, median of {len(rows) // 2} rounds | {models[0]} | {models[1]} | pruned / unpruned |")
print("|---|---:|---:|---:|")
for k, name in fields:
    a, b = median[models[0]][k], median[models[1]][k]
    print(f"| {name} | {a:.0f} | {b:.0f} | {b / a:.2f} |")
PY
rm -f "$out"
