#!/usr/bin/env bash
# The ready-made camera file (shipped/README.md, "A camera's model"): PhysiCLeAR's model to ship,
# `pvt3 final` of the headline cross-validation of docs/results.md ("Camera sets beside their
# anchors"), trained on every touch; and a touch of the set for the README's command. Prints the
# file's row of shipped/README.md's camera table.
#
#   bash shipped/make_camera.sh [PHYSICLEAR.npz [CV]]
#
# PHYSICLEAR.npz (default physiclear-30x40.npz) is the import of clear-nus/octopi's videos
# (docs/camera.md): pvt3 import octopi/dataset --name '{class}_*' --size 30x40 --allow-short
# --out physiclear-30x40.npz. CV (default runs/physiclear) is its cross-validation, made when
# absent: pvt3 cv --data PHYSICLEAR.npz --seeds 0,1,2 --jobs 2 (about 50 minutes on 2 cores), then
# the final model (about 4 minutes). PVT3=path/to/pvt3 picks the binary.
set -euo pipefail
cd "$(dirname "$0")/.."
data=${1:-physiclear-30x40.npz}
cv=${2:-runs/physiclear}
pvt3=${PVT3:-target/release/pvt3}
[ -x "$pvt3" ] || cargo build --release -p pvt3-trainer
python=target/onnx-venv/bin/python
[ -x "$python" ] || { echo "shipped/make_camera.sh: needs the tests' venv (cargo test --profile ci --workspace makes it)" >&2; exit 1; }
[ -f "$data" ] || { echo "shipped/make_camera.sh: no $data: import PhysiCLeAR first (see the top of this script)" >&2; exit 1; }
[ -f "$cv/cv.json" ] || "$pvt3" cv --data "$data" --seeds 0,1,2 --jobs 2 --out "$cv"
resume=()
[ -d "$cv/final" ] && resume=(--resume)
"$pvt3" final "$cv" --data "$data" -o shipped/physiclear.onnx "${resume[@]}" >/dev/null

# The set's first touch, as the import stored it: 8-bit frames of 30 x 40 RGB (the file reads
# them as it reads any window; a robot pushes the camera's own 240 x 320 frames instead).
"$python" - "$data" <<'PY'
import sys
import numpy as np
d = np.load(sys.argv[1])
np.save("shipped/physiclear-touch.npy", d["x"][0])
PY
answer=$(target/release/pvt3-run shipped/physiclear.onnx shipped/physiclear-touch.npy 2>/dev/null \
  || cargo run -q --release -p pvt3-runtime --bin pvt3-run -- shipped/physiclear.onnx shipped/physiclear-touch.npy)
"$python" - "$data" "$answer" "$(sha256sum shipped/physiclear.onnx | cut -d' ' -f1)" <<'PY'
import json, sys
import onnx
import numpy as np
data, answer, sha = sys.argv[1:]
d = np.load(data)
names = bytes(d["class_names"]).decode().split("\n")
meta = {p.key: p.value for p in onnx.load("shipped/physiclear.onnx").metadata_props}
e = json.loads(meta["pvt3.provenance"])["expected"]
lo, hi = e["ci95_test_accuracy"]
_, cls, label, _ = answer.split()
print("| file | expected accuracy (its cross-validation) | its touch's class | answered | SHA-256 |")
print(f"| `shipped/physiclear.onnx` | {e['mean_test_accuracy']:.4f} ± {e['std_test_accuracy']:.4f} [{lo:.4f}, {hi:.4f}] "
      f"| {names[int(d['y'][0])]} | {label} | {sha} |")
PY
