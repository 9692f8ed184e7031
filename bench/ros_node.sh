#!/usr/bin/env bash
# What pvt3-ros costs on a ROS 2 graph, the table of docs/benchmarks.md ("A ROS 2 node"): the
# node (a release build, pinned to one core) on the shipped camera file, fed by a driver through
# a zenoh router on 127.0.0.1 (bench/ros_node.py), at a DIGIT's 60 fps for SECONDS and a
# GelSight's 25 fps for a fifth of that: each touch's time from the publish of its last frame to
# its answer's arrival at the router (and at a Python listener) beside the runtime's own time on
# that frame, the node's CPU share and resident
# memory sampled every second. Then the static aarch64 node's size, as a robot takes it
# (`--profile robot`, without default features: the small runtime's).
#
#   bash bench/ros_node.sh [SECONDS]   # default 600
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-600}
python=target/onnx-venv/bin/python
"$python" -c "import zenoh, rosbags, xxhash, onnx" 2>/dev/null ||
  { echo "bench/ros_node.sh: needs the tests' venv (bash tests/run.sh makes it: target/onnx-venv)" >&2; exit 1; }
echo "building pvt3-ros (release, and static for aarch64)" >&2
cargo build -q --release -p pvt3-ros
(source tests/aarch64-env.sh && cargo build -q --profile robot --target aarch64-unknown-linux-musl -p pvt3-ros --no-default-features)
echo "| file | fps | run | publish to answer at the router, p50 / p99 | runtime on the last frame, p50 / p99 | difference, p99 | at the Python listener, p50 / p99 | CPU share, mean (max) | resident memory, first / last / max | its growth a minute, after the first |"
echo "|---|---:|---|---|---|---:|---|---|---|---:|"
"$python" bench/ros_node.py target/release/pvt3-ros shipped/physiclear.onnx image 60 "$seconds"
"$python" bench/ros_node.py target/release/pvt3-ros shipped/physiclear.onnx image 25 $((seconds / 5))
node=target/aarch64-unknown-linux-musl/robot/pvt3-ros
echo
echo "The static aarch64 node (\`$node\`): $(stat -c %s $node | awk '{ printf "%.1f MiB", $1 / 2^20 }'), $(file -b $node | cut -d, -f1-2)."
