#!/usr/bin/env bash
# Training speed, candle against PyTorch: `pvt3 bench train` (fused blocks, and with --composed the
# same blocks as plain candle ops) and the identical model in PyTorch on CPU, for both presets at
# each thread count, same batch and steps, alternating within every round; writes the table of
# docs/training-speed.md (the analysis below its "## Where the time goes" heading is kept).
# PyTorch comes from PyPI into target/bench-venv (a large download: the wheel pulls CUDA
# libraries), so this is a benchmark, never part of the tests.
#
#   bash bench/train_speed.sh     # STEPS=20 BATCH=32 ROUNDS=3 THREADS="1 2" PRESETS="icub20 biotac20"
set -euo pipefail
cd "$(dirname "$0")/.."
STEPS=${STEPS:-20} BATCH=${BATCH:-32} ROUNDS=${ROUNDS:-3}
THREADS=${THREADS:-1 2} PRESETS=${PRESETS:-icub20 biotac20}
venv=target/bench-venv
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
"$venv/bin/python" -c "import torch, numpy, safetensors" 2>/dev/null || "$venv/bin/pip" install -q torch numpy safetensors
cargo build --release -q
results=$(mktemp)
tag() { python3 -c 'import json,sys; r=json.loads(sys.stdin.read()); r.update(preset=sys.argv[1], threads=int(sys.argv[2])); print(json.dumps(r))' "$@"; }
for round in $(seq "$ROUNDS"); do
  for preset in $PRESETS; do
    for t in $THREADS; do
      echo "round $round/$ROUNDS: $preset, $t thread(s)" >&2
      ./target/release/pvt3 --threads "$t" bench train --preset "$preset" --steps "$STEPS" --batch-size "$BATCH" | tag "$preset" "$t" >> "$results"
      ./target/release/pvt3 --threads "$t" bench train --composed --preset "$preset" --steps "$STEPS" --batch-size "$BATCH" | tag "$preset" "$t" >> "$results"
      OMP_NUM_THREADS=$t "$venv/bin/python" bench/pvt3_torch.py --preset "$preset" --steps "$STEPS" --batch-size "$BATCH" --threads "$t" | tag "$preset" "$t" >> "$results"
    done
  done
done
"$venv/bin/python" - "$results" "$STEPS" "$BATCH" "$ROUNDS" "$(git rev-parse --short HEAD)" <<'PY'
import json, statistics, sys, platform
path, steps, batch, rounds, commit = sys.argv[1:]
rows = [json.loads(l) for l in open(path)]
runs = {}
for r in rows:
    kind = "pytorch" if r["framework"].startswith("pytorch") else ("composed" if "composed" in r["framework"] else "fused")
    runs.setdefault((r["preset"], r["threads"], kind), []).append(r["samples_per_second"])
torch_name = next(r["framework"] for r in rows if r["framework"].startswith("pytorch"))
cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), platform.processor())
cell = lambda v: f"**{statistics.median(v):.0f}** ({', '.join(f'{x:.0f}' for x in v)})"
out = [
    "# Training speed: candle against PyTorch",
    "",
    "One optimiser step = forward with dropout, label-smoothed cross-entropy, backward, gradient",
    "clipping and AdamW, on random inputs, batch " + batch + ". PyTorch runs the identical model",
    "(`bench/pvt3_torch.py`, which first reproduces the golden logits to "
    f"{max(r.get('golden_max_abs_error', 0) for r in rows):.1e}). *fused*: pvt3 as it trains (each",
    "transformer block and the embedding one candle op with its own backward); *composed*: the same",
    "model as plain candle ops (`pvt3 bench train --composed`), as pvt3 trained before the fused ops",
    "(its optimiser loop and dropout draws are today's).",
    "",
    f"Reproduce: `bash bench/train_speed.sh` (here STEPS={steps} BATCH={batch} ROUNDS={rounds}, commit {commit}).",
    "The three alternate within every round; a cell is the median samples/s, the rounds in brackets.",
    "",
    f"Machine: {cpu}, {platform.machine()}; {torch_name}.",
    "",
    "| preset | threads | candle fused | candle composed | PyTorch | fused / PyTorch | composed / PyTorch |",
    "|---|---|---|---|---|---|---|",
]
for (preset, threads) in sorted({(p, t) for p, t, _ in runs}, key=lambda k: (k[0] != "icub20", k[1])):
    f, c, p = (runs[(preset, threads, k)] for k in ("fused", "composed", "pytorch"))
    ratio = lambda a: statistics.median(a) / statistics.median(p)
    out.append(f"| {preset} | {threads} | {cell(f)} | {cell(c)} | {cell(p)} | **{ratio(f):.2f}** | {ratio(c):.2f} |")
out.append("")
open("docs/training-speed.md.table", "w").write("\n".join(out) + "\n")
print("\n".join(out))
PY
# Keep the hand-written analysis below the generated table.
if [ -f docs/training-speed.md ] && grep -q '^## Where the time goes' docs/training-speed.md; then
  sed -n '/^## Where the time goes/,$p' docs/training-speed.md >> docs/training-speed.md.table
fi
mv docs/training-speed.md.table docs/training-speed.md
rm -f "$results"
