"""Patch selection beside the unpruned model (docs/camera.md, "Patch selection beside the head"),
from a finished `pvt3 cv ... --set patch_selection=true --prune-patches P` directory: each form's
parameters and multiply-adds after baking (`pvt3 info`), validation and test accuracy, the change
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


def summary(values):
    """Mean ± std over runs, the seed means and the 95 % interval of the seed means (t, 2 degrees)."""
    by_seed = {}
    for seed, v in values:
        by_seed.setdefault(seed, []).append(v)
    seed_means = [statistics.mean(v) for v in by_seed.values()]
    flat = [v for _, v in values]
    mean = statistics.mean(flat)
    text = f"{mean:.4f} ± {statistics.stdev(flat):.4f}"
    if len(seed_means) > 1:
        t = {1: 12.706, 2: 4.303, 3: 3.182, 4: 2.776}[len(seed_means) - 1]
        half = t * statistics.stdev(seed_means) / len(seed_means) ** 0.5
        text += f" [{statistics.mean(seed_means) - half:.4f}, {statistics.mean(seed_means) + half:.4f}]"
    return text + " (seed means " + ", ".join(f"{m:.4f}" for m in seed_means) + ")"


def main():
    cv = Path(sys.argv[1])
    runs = sorted(p for p in cv.glob("seed*/fold*") if (p / "pruned" / "result.json").exists())
    result = lambda run: json.loads((run / "result.json").read_text())
    rows = {"unpruned": [], "pruned": []}
    changes, kept = [], Counter()
    for run in runs:
        seed = int(run.parent.name[4:])
        before, after = result(run), result(run / "pruned")
        rows["unpruned"].append((seed, before))
        rows["pruned"].append((seed, after))
        changes.append(after["test_accuracy"] - before["test_accuracy"])
        kept.update(kept_patches(run / "pruned" / "model"))
    print(f"`{cv}`, {len(runs)} runs\n")
    print("| | parameters | multiply-adds a touch | validation, mean | test, mean ± std [95 % interval] |")
    print("|---|---:|---:|---:|---|")
    for name, model in [("unpruned", runs[0] / "model"), ("pruned", runs[0] / "pruned" / "model")]:
        params, madds = baked(model)
        val = statistics.mean(r["val_accuracy"] for _, r in rows[name])
        test = summary([(s, r["test_accuracy"]) for s, r in rows[name]])
        print(f"| {name} | {params:,} | {madds / 1e6:.2f} M | {val:.4f} | {test} |")
    better = sum(c > 1e-9 for c in changes)
    worse = sum(c < -1e-9 for c in changes)
    print(f"\nPaired change in test accuracy: {100 * statistics.mean(changes):+.2f} points on average; "
          f"better in {better} runs, worse in {worse}, the same in {len(changes) - better - worse}.")
    perfect = sum(r["val_accuracy"] == 1.0 for _, r in rows["unpruned"])
    print(f"Validation perfect in {perfect} of the {len(runs)} unpruned runs.")
    print("Patches kept (index: runs): " + ", ".join(f"{i}: {n}" for i, n in sorted(kept.items(), key=lambda kv: (-kv[1], kv[0]))))


if __name__ == "__main__":
    main()
