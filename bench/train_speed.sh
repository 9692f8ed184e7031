#!/usr/bin/env bash
# Training speed of the icub20 preset: candle (`pvt3 bench train`) and the identical model in
# PyTorch on CPU, same batch, steps and threads, alternating in one run; writes
# docs/training-speed.md. PyTorch comes from PyPI into target/bench-venv (a large download: the
# wheel pulls CUDA libraries), so this is a benchmark, never part of the tests.
#
#   bash bench/train_speed.sh            # STEPS=20 BATCH=32 THREADS=1 ROUNDS=3 by default
set -euo pipefail
cd "$(dirname "$0")/.."
STEPS=${STEPS:-20} BATCH=${BATCH:-32} THREADS=${THREADS:-1} ROUNDS=${ROUNDS:-3}
venv=target/bench-venv
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
"$venv/bin/python" -c "import torch, numpy, safetensors" 2>/dev/null || "$venv/bin/pip" install -q torch numpy safetensors
cargo build --release -q
results=$(mktemp)
for round in $(seq "$ROUNDS"); do
  echo "round $round/$ROUNDS" >&2
  ./target/release/pvt3 --threads "$THREADS" bench train --steps "$STEPS" --batch-size "$BATCH" >> "$results"
  OMP_NUM_THREADS=$THREADS "$venv/bin/python" bench/pvt3_torch.py --steps "$STEPS" --batch-size "$BATCH" --threads "$THREADS" >> "$results"
done
"$venv/bin/python" - "$results" "$STEPS" "$BATCH" "$THREADS" "$ROUNDS" <<'PY'
import json, statistics, sys, platform, subprocess
path, steps, batch, threads, rounds = sys.argv[1:]
rows = [json.loads(l) for l in open(path)]
by = {}
for r in rows:
    by.setdefault(r["framework"], []).append(r["samples_per_second"])
cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), platform.processor())
candle = statistics.median(next(v for k, v in by.items() if k == "candle"))
torch_name, torch_rates = next((k, v) for k, v in by.items() if k != "candle")
torch = statistics.median(torch_rates)
out = [
    "# Training speed: candle against PyTorch",
    "",
    "The `icub20` preset (64,272 parameters), one optimiser step = forward with dropout, label-smoothed",
    "cross-entropy, backward, gradient clipping and AdamW, on random inputs. PyTorch runs the identical",
    "model (`bench/pvt3_torch.py`, which first reproduces the golden logits to "
    f"{max(r.get('golden_max_abs_error', 0) for r in rows):.1e}).",
    "",
    f"Reproduce: `bash bench/train_speed.sh` (here STEPS={steps} BATCH={batch} THREADS={threads} ROUNDS={rounds};",
    "the two alternate within one run, and each figure is the median of the rounds).",
    "",
    f"Machine: {cpu}, {threads} thread(s).",
    "",
    "| framework | batch | samples / s (median) | every round |",
    "|---|---|---|---|",
    f"| candle (pvt3) | {batch} | {candle:.1f} | {', '.join(f'{v:.1f}' for v in by['candle'])} |",
    f"| {torch_name} | {batch} | {torch:.1f} | {', '.join(f'{v:.1f}' for v in torch_rates)} |",
    "",
    f"**candle / PyTorch = {candle / torch:.2f}**",
    "",
]
open("docs/training-speed.md.table", "w").write("\n".join(out) + "\n")
print("\n".join(out))
PY
# Keep the hand-written analysis below the generated table.
if [ -f docs/training-speed.md ] && grep -q '^## Where the time goes' docs/training-speed.md; then
  sed -n '/^## Where the time goes/,$p' docs/training-speed.md >> docs/training-speed.md.table
fi
mv docs/training-speed.md.table docs/training-speed.md
rm -f "$results"
