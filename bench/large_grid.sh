#!/usr/bin/env bash
# The layout of a large taxel grid, chosen on data (docs/results.md, "A large taxel grid"): two
# SYNTHETIC 32 x 32 pressure-array sets (bench/synthetic_grid.py: a texture sliding, a shape
# pressed), each imported from CSV as a user would and trained by `pvt3 cv --seeds 0,1,2` with
# the image's layout (the default for a grid this large) and with the channels' (the BioTac
# layout, a token of every taxel, by --config); beside them a ridge on the raw values on the same
# folds (bench/pixel_ridge.py). Prints each cross-validation's table.
#
#   bash bench/large_grid.sh [OUT_DIR]     # default target/large-grid; about 75 minutes on 2 cores
set -euo pipefail
case ${1:-} in -h | --help) sed -n '2,9p' "$0"; exit 0 ;; esac
here=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-$here/target/large-grid}
python=$here/target/onnx-venv/bin/python
[ -x "$python" ] || { echo "no $python: run bash tests/run.sh once (it makes the venv), or make a venv with numpy there" >&2; exit 1; }
cargo build --release --quiet --manifest-path "$here/Cargo.toml" -p pvt3-trainer --bin pvt3
pvt3=$here/target/release/pvt3
mkdir -p "$out"
cd "$out"
for set in slide press; do
  [ -d "$set" ] || "$python" "$here/bench/synthetic_grid.py" "$set" "$set"
  "$pvt3" import "$set" --grid 32x32 --out "$set.npz"
  # The BioTac preset laid over the set's whole grid, a token a frame: what an array's layout
  # derives for frames smaller than an image's (the tubelet that keeps about 40 tokens is 1 here).
  "$pvt3" info biotac20 --json | "$python" -c '
import json, sys
import numpy as np
data, c = np.load(sys.argv[1]), json.load(sys.stdin)
_, height, width, frames = data["x"].shape
c.update(height=height, width=width, frames=frames, patch_height=height, patch_width=width, tubelet=1, classes=int(data["y"].max()) + 1)
json.dump(c, open(sys.argv[2], "w"), indent=1)' "$set.npz" "$set-channels.json"
  for layout in image channels; do
    config=()
    [ "$layout" = image ] || config=(--config "$set-channels.json")
    echo "== $set, the $layout layout"
    "$pvt3" cv --data "$set.npz" "${config[@]}" --seeds 0,1,2 --jobs 2 --out "runs/$set-$layout" 2>&1 | grep -v '^note\|^seed [0-9]: note'
  done
  echo "== $set, a ridge on the raw values (the same folds)"
  "$python" "$here/bench/pixel_ridge.py" "$set.npz" "runs/$set-image" | tail -1
done
