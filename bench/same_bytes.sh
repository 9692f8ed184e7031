#!/usr/bin/env bash
# A refactor changes no behaviour: the trainer built at BASE and the one in this working tree
# train the same short runs, and every file they write is the same bytes (weights, optimiser
# states, masks, metrics.jsonl, checkpoints' JSON, pictures, the exported .onnx), but for the
# wall-clock seconds that metrics.jsonl, result.json and state.json record.
#
#   bash bench/same_bytes.sh BASE [FABRICSLIDE [PHYSICLEAR]]
#   e.g. bash bench/same_bytes.sh HEAD~3 ../data/FabricSlide ../data/octopi
#
# The runs, two epochs each (a pruned run fine-tunes one more):
#   icub     iCub-20, 50 % of channels and 30 % of frames pruned, exported;
#   biotac   BioTac-20 with the spectral head, 60 % of channels pruned, exported;
#   joint    iCub-20 learnt jointly with BioTac-20 (--joint, pulled together from epoch 1);
#   fabric   FabricSlide imported from its CSV files (the .npz compared too), the positive speeds
#            held out, with --extrapolate and --extrapolate-levels; only when FABRICSLIDE is given
#            (a checkout of wngfra/FabricSlide);
#   camera   PhysiCLeAR imported from its GelSight videos at 30 × 40 (the .npz compared too) and
#            trained with the camera's derived layout, its head fitted, exported; only when
#            PHYSICLEAR is given (a checkout of clear-nus/octopi; FFmpeg decodes, about 2 minutes
#            an import).
# Both binaries are built in the tests' profile (`ci`), each in a target directory of its own (cargo
# names a workspace's crates by their path in it, so two checkouts would share their files); BASE
# is checked out as a git worktree under target/same-bytes/. Prints one line per run and fails on
# the first difference.
set -euo pipefail
cd "$(dirname "$0")/.."
base=${1:?usage: bash bench/same_bytes.sh BASE [FABRICSLIDE [PHYSICLEAR]]}
fabric=${2:-}
physiclear=${3:-}
out=target/same-bytes
rm -rf "$out/runs"
mkdir -p "$out/runs"
if [ ! -d "$out/base" ]; then
  git worktree add -q --detach "$out/base" "$base"
else
  git -C "$out/base" checkout -q --detach "$(git rev-parse "$base")"
fi
for who in base head; do
  tree=. target_dir=$PWD/target
  [ "$who" = head ] || tree=$out/base target_dir=$PWD/$out/target
  (cd "$tree" && CARGO_TARGET_DIR=$target_dir cargo build -q --profile ci -p pvt3-trainer --bin pvt3)
  cp "$target_dir/ci/pvt3" "$out/pvt3-$who"
done

icub=(--data data/icub20.npz)
biotac=(--data data/biotac20.npz)
runs=(
  "icub|train ${icub[*]} --epochs 2 --prune-channels 50 --prune-frames 30 --fine-tune-epochs 1 --export OUT/model.onnx"
  "biotac|train ${biotac[*]} --epochs 2 --set spectral_bands=16 --prune-channels 60 --fine-tune-epochs 1 --export OUT/model.onnx"
  "joint|train ${icub[*]} --joint data/biotac20.npz --joint-after 1 --epochs 2"
)
if [ -n "$fabric" ]; then
  for who in base head; do
    "$out/pvt3-$who" import "$fabric/data/fabric" --name '{class}_F{force}_V{speed}mmps_*' --out "$out/runs/fabric-$who.npz" >/dev/null
  done
  cmp "$out/runs/fabric-base.npz" "$out/runs/fabric-head.npz"
  echo "fabric import: the same bytes"
  runs+=("fabric|train --data $out/runs/fabric-head.npz --hold-out speed=10,20,50,100,120,150 --extrapolate 1 --extrapolate-levels --epochs 2")
fi
if [ -n "$physiclear" ]; then
  for who in base head; do
    "$out/pvt3-$who" import "$physiclear/dataset" --name '{class}_*' --size 30x40 --allow-short --out "$out/runs/physiclear-$who.npz" >/dev/null
  done
  cmp "$out/runs/physiclear-base.npz" "$out/runs/physiclear-head.npz"
  echo "physiclear import: the same bytes"
  runs+=("camera|train --data $out/runs/physiclear-head.npz --epochs 2 --export OUT/model.onnx")
fi

for run in "${runs[@]}"; do
  name=${run%%|*}
  args=${run#*|}
  for who in base head; do
    # One directory name for both (pictures' titles name it), moved aside after.
    dir=$out/runs/$name
    # shellcheck disable=SC2086 # args is a word list of options
    "$out/pvt3-$who" ${args//OUT/$dir} --out "$dir" >"$dir-$who.log" 2>&1 || { cat "$dir-$who.log" >&2; exit 1; }
    mv "$dir" "$dir-$who"
  done
  python3 - "$out/runs/$name-base" "$out/runs/$name-head" "$name" <<'EOF'
import json, os, sys
base, head, name = sys.argv[1:]
# Wall-clock seconds differ between any two runs; nothing else may.
TIMES = {"seconds", "wall_seconds"}
def files(root):
    return sorted(os.path.relpath(os.path.join(d, f), root) for d, _, fs in os.walk(root) for f in fs)
def untimed(path):
    def drop(v):
        if isinstance(v, dict):
            return {k: drop(x) for k, x in v.items() if k not in TIMES}
        if isinstance(v, list):
            return [drop(x) for x in v]
        return v
    text = open(path).read()
    if path.endswith(".jsonl"):
        return [drop(json.loads(line)) for line in text.splitlines()]
    return drop(json.loads(text))
names = files(base)
assert names == files(head), f"{name}: different files\n  base {names}\n  head {files(head)}"
timed = 0
for f in names:
    a, b = os.path.join(base, f), os.path.join(head, f)
    if open(a, "rb").read() == open(b, "rb").read():
        continue
    assert f.endswith((".json", ".jsonl")) and untimed(a) == untimed(b), f"{name}: {f} differs"
    timed += 1
print(f"{name}: {len(names)} files the same bytes, {timed} of them but for wall-clock seconds")
EOF
done
