"""The comparison table of docs/results.md: one row per model, each a set of finished runs (one
per validation fold) under the published protocol, with parameters, multiply-adds, per-fold test
accuracy, mean ± std and training wall time, and the published figure beside it.

    python3 bench/comparison.py                           # the two tables of docs/results.md
    python3 bench/comparison.py 'LABEL|PUBLISHED|GLOB' ...  # one table of your own rows

GLOB matches run directories holding `result.json` (e.g. `runs/cv-vit-icub/seed0/fold?`, or
`runs/cv-icub20-l1/seed0/fold?/pruned`); PUBLISHED is the paper's figure or `—`. Sizes come from
`pvt3 info` of the first run: the baked (deployed) size for a pruned PVT³ model, the trainable
parameters otherwise.
"""
import glob
import json
import re
import statistics
import subprocess
import sys
from pathlib import Path

PVT3 = "./target/release/pvt3"


def size(run):
    out = subprocess.run([PVT3, "info", str(run)], capture_output=True, text=True, check=True).stdout
    provenance = json.loads((run / "model" / "provenance.json").read_text())
    baked = re.search(r"after baking\s+(\d+) parameters, (\d+) multiply-adds per sample", out)
    if provenance.get("pruning") and baked:
        return int(baked[1]), int(baked[2])
    return int(re.search(r"parameters\s+(\d+) trainable", out)[1]), int(re.search(r"mult-adds\s+(\d+) per sample", out)[1])


def row(spec):
    label, published, pattern = spec.split("|")
    runs = sorted(Path(p) for p in glob.glob(pattern) if (Path(p) / "result.json").exists())
    if not runs:
        sys.exit(f"{label}: no finished run matches {pattern}")
    results = [json.loads((r / "result.json").read_text()) for r in runs]
    tests = [r["test_accuracy"] for r in results]
    params, macs = size(runs[0])
    std = statistics.stdev(tests) if len(tests) > 1 else 0.0
    folds = " / ".join(f"{t:.3f}" for t in tests)
    minutes = sum(r["wall_seconds"] for r in results) / 60
    # Means of a few fold accuracies often end in a 5 at the fifth decimal: round it up, as `pvt3 cv` prints.
    mean = statistics.mean(tests) + 1e-12
    return f"| {label} | {params:,} | {macs / 1e6:.2f} M | {folds} | **{mean:.4f} ± {std:.4f}** | {published} | {minutes:.0f} |"


# The rows of docs/results.md. Published: the PVT³ paper's ViViT and best PVT³ (with random
# pruning); the baselines' own figures are not in the sources this project has.
TABLES = {
    "iCub-20": [
        "ViT|—|runs/cv-vit-icub/seed0/fold?",
        "RAEC|—|runs/cv-raec-icub/seed0/fold?",
        "ViViT backbone (PVT³ unpruned, masks untrained)|0.9224|runs/cv-icub20/seed0/fold?",
        "PVT³, trained masks, unpruned|—|runs/cv-icub20-l1/seed0/fold?",
        "PVT³ pruned: 50 % of channels|—|runs/cv-icub20-l1/seed0/fold?/pruned",
        "PVT³ pruned: 50 % of frames|—|runs/frames-icub20/fold?-p50",
        "PVT³ with random pruning|0.9425|runs/cv-rp-icub/seed0/fold?",
    ],
    "BioTac-20": [
        "ViT|—|runs/cv-vit-biotac/seed0/fold?",
        "RAEC|—|runs/cv-raec-biotac/seed0/fold?",
        "ViViT backbone (PVT³ unpruned, masks untrained)|0.9659|runs/cv-biotac20-frame/seed0/fold?",
        "PVT³, trained masks, unpruned|—|runs/cv-biotac20-l1/seed0/fold?",
        "PVT³ pruned: 50 % of frames|—|runs/cv-biotac20-l1/seed0/fold?/pruned",
        "PVT³ with random pruning|0.9798|runs/cv-rp-biotac/seed0/fold?",
    ],
}


def table(specs):
    print("| model | parameters | multiply-adds | test accuracy per fold (0–3) | mean ± std | published | training (min) |")
    print("|---|---:|---:|---|---:|---:|---:|")
    for spec in specs:
        print(row(spec))


def main():
    if sys.argv[1:]:
        table(sys.argv[1:])
        return
    for name, specs in TABLES.items():
        print(f"### {name}\n")
        table(specs)
        print()


if __name__ == "__main__":
    main()
