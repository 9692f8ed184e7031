#!/usr/bin/env bash
# The ready-made files in shipped/ (shipped/README.md): each sensor's headline model of
# docs/results.md ("One file per sensor"), trained as its row's run of seed 0 with validation
# fold 0, so that fold 4, the shipped data sets' test fold, still tests it. Resumes where it
# stopped. Prints each file's row of shipped/README.md's table: its test accuracy on fold 4 (the
# trainer's evaluation; tests/shipped.rs checks the runtime answers the same) and its SHA-256.
#
#   bash shipped/make.sh          PVT3=path/to/pvt3 picks the binary; runs go to runs/shipped/
#
# iCub-20: the anytime-icub row (PVT³, --prefix-training 0.5, 60 % of channels pruned).
# BioTac-20: the e300-distill-spectral-anytime-mixup-biotac row: the spectral head, trained for
# early answers with mixup, taught by the whole-window spectral runs of its split (here seeds 0,
# 1 and 2 of validation fold 0, as the row's runs were taught by theirs), 300 epochs, 60 % of
# channels pruned. Two runs side by side, one thread each: about an hour on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
pvt3=${PVT3:-target/release/pvt3}
[ -x "$pvt3" ] || cargo build --release -p pvt3-trainer
out=runs/shipped
python=target/onnx-venv/bin/python
[ -x "$python" ] || { echo "shipped/make.sh: needs the tests' venv (cargo test --profile ci --workspace makes it)" >&2; exit 1; }

# One run of a row: cv --only seed=S,fold=0 into DIR, resumed if begun.
run() {
    local dir=$1 seed=$2
    shift 2
    local resume=()
    [ -d "$dir/seed$seed/fold0" ] && resume=(--resume)
    echo "== $pvt3 --threads 1 cv $* --only seed=$seed,fold=0 --out $dir"
    "$pvt3" --threads 1 cv "$@" --only "seed=$seed,fold=0" --out "$dir" "${resume[@]}" >"$dir.seed$seed.log" 2>&1
}
mkdir -p "$out"
pruned60=(--prune-channels 60 --fine-tune-epochs 20)
biotac=(--data data/biotac20.npz "${pruned60[@]}" --l1 0.25 --mask-lr 10 --set spectral_bands=16)
{
    run "$out/icub20" 0 --data data/icub20.npz "${pruned60[@]}" --prefix-training 0.5 --epochs 100
    run "$out/biotac20-teachers" 2 "${biotac[@]}" --epochs 100
} &
first=$!
run "$out/biotac20-teachers" 0 "${biotac[@]}" --epochs 100
run "$out/biotac20-teachers" 1 "${biotac[@]}" --epochs 100
wait "$first"
run "$out/biotac20" 0 "${biotac[@]}" --prefix-training 0.5 --mixup 0.2 --distill "$out/biotac20-teachers" --epochs 300

# Each file, its window for the README's first command, and its row.
echo "| file | test accuracy on fold 4 | touches right | SHA-256 |"
for set in icub20 biotac20; do
    model=$out/$set/seed0/fold0/pruned
    "$pvt3" export "$model" -o "shipped/$set.onnx" >/dev/null
    accuracy=$("$pvt3" eval "$model" --json | "$python" -c 'import json, sys
e = json.load(sys.stdin)
right = sum(e["confusion"][c][c] for c in range(len(e["confusion"])))
print("{:.4f} | {} of {}".format(e["accuracy"], right, e["touches"]))')
    "$python" - "$set" <<'EOF'
import sys
import numpy as np
name = sys.argv[1]
d = np.load(f"data/{name}.npz")
first = int(np.flatnonzero(d["fold"] == 4)[0])  # the test fold's first touch
np.save(f"shipped/{name}-touch.npy", d["x"][first].astype(np.float32))
EOF
    echo "| \`shipped/$set.onnx\` | $accuracy | $(sha256sum "shipped/$set.onnx" | cut -d' ' -f1) |"
done
