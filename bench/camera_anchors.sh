#!/usr/bin/env bash
# The anchors of a camera set on the folds of its `pvt3 cv` run (docs/results.md, "Camera sets
# beside their anchors"): a ridge on the raw values (bench/pixel_ridge.py), the ridge on 303 image
# statistics (bench/camera_linear.py) and a small CNN in PyTorch (bench/small_cnn.py), each
# printing its runs and its mean ± std, seed means and 95 % interval.
#
#   bash bench/camera_anchors.sh DATA.npz CV_DIR
#
# numpy comes from target/onnx-venv (the tests' venv); PyTorch is installed into target/cnn-venv
# on first use (PyPI's wheel, about 3 GB with its CUDA libraries, which run on CPU here).
set -euo pipefail
[ $# -eq 2 ] || { sed -n '2,10p' "$0"; exit 2; }
here=$(cd "$(dirname "$0")/.." && pwd)
data=$1 cv=$2
numpy=$here/target/onnx-venv/bin/python
[ -x "$numpy" ] || { echo "no $numpy: run bash tests/run.sh once (it makes the venv), or make a venv with numpy there" >&2; exit 1; }
cnn=$here/target/cnn-venv
if ! "$cnn/bin/python" -c 'import torch' 2>/dev/null; then
  python3 -m venv "$cnn"
  "$cnn/bin/pip" install -q torch numpy
fi
echo "== ridge on the raw values"
"$numpy" "$here/bench/pixel_ridge.py" "$data" "$cv"
echo "== ridge on 303 image statistics"
"$numpy" "$here/bench/camera_linear.py" "$data" "$cv"
echo "== small CNN"
"$cnn/bin/python" "$here/bench/small_cnn.py" "$data" "$cv"
