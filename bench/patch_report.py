"""Patch selection beside the unpruned model (docs/camera.md, "Patch selection beside the head"),
from a finished `pvt3 cv ... --set patch_selection=true --prune-patches P` directory: each form's
parameters and multiply-adds after baking (`pvt3 info`), validation accuracy, the test accuracy
`pvt3 cv` summarised (cv.json: mean ± std, interval, seed means), the change
pruning made paired run by run, and which patches the pruned runs kept (row order, the nonzero
entries of each pruned model's `patch_mask`).

    python3 bench/patch_report.py CV_DIR
"""
import json
import re
import statistics
import struct
import subprocess
import sys
from array import array
from collections import Counter
from pathlib import Path


def baked(model):
    out = subprocess.run(["./target/release/pvt3", "info", str(model)], capture_output=True, text=True, check=True).stdout
    m = re.search(r"after baking\s+(\d+) parameters, (\d+) multiply-adds per sample", out)
    return int(m[1]), int(m[2])


def kept_patches(model):
    """The indices of the patches whose mask entry is not zero."""
    raw = (model / "weights.safetensors").read_bytes()
    (n,) = struct.unpack("<Q", raw[:8])
    entry = json.loads(raw[8 : 8 + n])["patch_mask"]
    start, end = entry["data_offsets"]
    mask = array("f")
    mask.frombytes(raw[8 + n + start : 8 + n + end])
    return [i for i, v in enumerate(mask) if v != 0.0]


def accuracy(cv, prefix):
    """The test accuracy `pvt3 cv` summarised in cv.json (`prefix` "" or "pruned_"): mean ± std,
    its 95 % interval and the seed means."""
    lo, hi = cv[f"{prefix}ci95_test_accuracy"]
    means = ", ".join(f"{m:.4f}" for m in cv[f"{prefix}seed_means"])
    return f"{cv[f'{prefix}mean_test_accuracy']:.4f} ± {cv[f'{prefix}std_test_accuracy']:.4f} [{lo:.4f}, {hi:.4f}] (seed means {means})"


def main():
    cv_dir = Path(sys.argv[1])
    cv = json.loads((cv_dir / "cv.json").read_text())
    runs = sorted(p for p in cv_dir.glob("seed*/fold*") if (p / "pruned" / "result.json").exists())
    result = lambda run: json.loads((run / "result.json").read_text())
    changes = [result(run / "pruned")["test_accuracy"] - result(run)["test_accuracy"] for run in runs]
    kept = Counter(i for run in runs for i in kept_patches(run / "pruned" / "model"))
    print(f"`{cv_dir}`, {len(runs)} runs\n")
    print("| | parameters | multiply-adds a touch | validation, mean | test, mean ± std [95 % interval] |")
    print("|---|---:|---:|---:|---|")
    for name, prefix, model in [("unpruned", "", runs[0] / "model"), ("pruned", "pruned_", runs[0] / "pruned" / "model")]:
        params, madds = baked(model)
        val = statistics.mean(r["val_accuracy"] for r in cv[f"{prefix}runs"])
        print(f"| {name} | {params:,} | {madds / 1e6:.2f} M | {val:.4f} | {accuracy(cv, prefix)} |")
    better = sum(c > 1e-9 for c in changes)
    worse = sum(c < -1e-9 for c in changes)
    print(f"\nPaired change in test accuracy: {100 * statistics.mean(changes):+.2f} points on average; "
          f"better in {better} runs, worse in {worse}, the same in {len(changes) - better - worse}.")
    perfect = sum(r["val_accuracy"] == 1.0 for r in cv["runs"])
    print(f"Validation perfect in {perfect} of the {len(cv['runs'])} unpruned runs.")
    print("Patches kept (index: runs): " + ", ".join(f"{i}: {n}" for i, n in sorted(kept.items(), key=lambda kv: (-kv[1], kv[0]))))


if __name__ == "__main__":
    main()
