#!/usr/bin/env bash
# The layout of a large taxel grid, chosen on data (docs/results.md, "A large taxel grid"): two
# SYNTHETIC 32 x 32 pressure-array sets (bench/synthetic_grid.py: a texture sliding, a shape
# pressed), each imported from CSV as a user would, once as the tactile array it is (the default)
# and once as a camera's images (`--sensor camera`), and trained by `pvt3 cv --seeds 0,1,2`;
# beside them a ridge on the raw values on the array runs' folds (bench/pixel_ridge.py). Prints
# each run's table; the two imports draw the same folds (the same touches, the same seeds).
#
#   bash bench/large_grid.sh [OUT_DIR]     # default target/large-grid; about 80 minutes on 2 cores
set -euo pipefail
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
  "$pvt3" import "$set" --grid 32x32 --sensor camera --out "$set-camera.npz"
  for layout in array camera; do
    data=$set.npz
    [ "$layout" = array ] || data=$set-camera.npz
    echo "== $set, the $layout layout"
    "$pvt3" cv --data "$data" --seeds 0,1,2 --jobs 2 --out "runs/$set-$layout" 2>&1 | grep -v '^note\|^seed [0-9]: note'
  done
  echo "== $set, a ridge on the raw values (the array runs' folds)"
  "$python" "$here/bench/pixel_ridge.py" "$set.npz" "runs/$set-array" | tail -1
done
