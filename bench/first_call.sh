#!/usr/bin/env bash
# The first call's cost (building the batch-1 plan, then classifying) of `pvt3-run` at this
# checkout against the runtime of another revision, side by side in one run: each round runs
# every model in a fresh process, old and new in turn, so that the machine's noise falls on both.
# Prints a markdown table of medians (and minima) for docs/benchmarks.md.
#
#   bash bench/first_call.sh REV [MODEL.onnx ...]     # default: the committed golden model
#   ROUNDS=10 bash bench/first_call.sh HEAD~1 target/deploy/*.onnx
#
# REV's pvt3-run is built from a git worktree into target/first-call/ (its own target directory:
# a cold build of tract, a few minutes, the first time).
set -euo pipefail
cd "$(dirname "$0")/.."
rev=${1:?usage: bash bench/first_call.sh REV [MODEL.onnx ...]}
shift
models=("$@")
[ ${#models[@]} -gt 0 ] || models=(tests/golden/icub20/model.onnx)
ROUNDS=${ROUNDS:-10}
old_dir=target/first-call
commit=$(git rev-parse --short "$rev")
tree="$old_dir/src-$commit"
[ -d "$tree" ] || git worktree add -q --detach "$tree" "$commit"
echo "building pvt3-run at $commit" >&2
(cd "$tree" && cargo build -q --release -p pvt3-runtime --bin pvt3-run --target-dir "$PWD/../target")
echo "building pvt3-run here" >&2
cargo build -q --release -p pvt3-runtime --bin pvt3-run
old="$old_dir/target/release/pvt3-run" new=target/release/pvt3-run
results=$(mktemp)
trap 'rm -f "$results"' EXIT
for round in $(seq "$ROUNDS"); do
  echo "round $round/$ROUNDS" >&2
  for m in "${models[@]}"; do
    for side in old new; do
      bin=$old
      [ "$side" = new ] && bin=$new
      # RUST_BACKTRACE makes every error tract raises and catches while it optimises capture a
      # backtrace; a robot runs without it.
      env -u RUST_BACKTRACE "$bin" --bench "$m" 1 0.2 | sed "s/^{/{\"side\":\"$side\",/" >> "$results"
    done
  done
done
python3 - "$results" "$commit" "$(git rev-parse --short HEAD)$(git diff --quiet HEAD -- runtime || echo +)" "$ROUNDS" "${models[*]}" <<'PY'
import collections, json, statistics, sys
results, old, new, rounds, models = sys.argv[1:]
rows = collections.defaultdict(list)
for line in open(results):
    r = json.loads(line)
    rows[(r["model"], r["side"])].append(r)
print(f"`bash bench/first_call.sh {old} {models}`, {rounds} rounds, a fresh process per measurement, old and new in turn:\n")
print(f"| model | first call at {old}: median (min) ms | first call at {new}: median (min) ms | batch 1 at {old} / {new} (µs) | `prepare(&[1], true)` at {old} / {new} (ms) |")
print("|---|---:|---:|---:|---:|")
for model in dict.fromkeys(m for m, _ in rows):
    o, n = rows[(model, "old")], rows[(model, "new")]
    med = lambda rs, k: statistics.median(r[k] for r in rs)
    first = lambda rs: f"{med(rs, 'batch1_first_call_ms'):.1f} ({min(r['batch1_first_call_ms'] for r in rs):.1f})"
    print(f"| `{model}` | {first(o)} | {first(n)} | {med(o, 'batch1_median_us'):.0f} / {med(n, 'batch1_median_us'):.0f} | {med(o, 'prepare_ms'):.1f} / {med(n, 'prepare_ms'):.1f} |")
PY
