"""Tables of docs/pruning.md from finished runs: test accuracy per fold before and after pruning,
with the parameters and multiply-adds of each model after baking (from `pvt3 info RUN`).

    python3 bench/pruning_report.py CV_DIR [FRAMES_DIR]

CV_DIR is a `pvt3 cv` directory (seed0/foldK, and seed0/foldK/pruned if run with --prune-channels
or --prune-frames; frames alone join the frame table);
FRAMES_DIR holds `foldK-pP` runs of `pvt3 prune CV_DIR/seed0/foldK --prune-frames P`.
"""
import json
import re
import statistics
import subprocess
import sys
from pathlib import Path


def baked(run):
    out = subprocess.run(["./target/release/pvt3", "info", str(run)], capture_output=True, text=True, check=True).stdout
    m = re.search(r"after baking\s+(\d+) parameters, (\d+) multiply-adds per sample, (\d+) of (\d+) temporal tokens kept", out)
    return int(m[1]), int(m[2]), f"{m[3]}/{m[4]}"


def test_accuracy(run):
    return json.loads((run / "result.json").read_text())["test_accuracy"]


def mean_std(values):
    return f"{statistics.mean(values):.4f} ± {statistics.stdev(values) if len(values) > 1 else 0:.4f}"


def main():
    cv = Path(sys.argv[1])
    folds = sorted(p for p in (cv / "seed0").glob("fold*") if (p / "result.json").exists())
    before = [test_accuracy(f) for f in folds]
    pruned = [f for f in folds if (f / "pruned" / "result.json").exists()]
    if pruned:
        provenance = json.loads((pruned[0] / "pruned" / "model" / "provenance.json").read_text())
        print(f"Pruning ({provenance.get('pruning')}), `{cv}`:\n")
        print("| fold | test before | test after | parameters before → after | multiply-adds before → after |")
        print("|---|---:|---:|---:|---:|")
        after = []
        for f in pruned:
            b, a = baked(f / "model"), baked(f / "pruned" / "model")
            after.append(test_accuracy(f / "pruned"))
            print(f"| {f.name[4:]} | {test_accuracy(f):.4f} | {after[-1]:.4f} | {b[0]:,} → {a[0]:,} ({a[0] / b[0]:.0%}) | "
                  f"{b[1] / 1e6:.2f} M → {a[1] / 1e6:.2f} M ({a[1] / b[1]:.0%}) |")
        print(f"| mean | {mean_std([test_accuracy(f) for f in pruned])} | {mean_std(after)} | | |")
    if len(sys.argv) < 3:
        return
    frames = Path(sys.argv[2])
    print(f"\nFrame pruning from the unpruned checkpoints of `{cv}`, `{frames}`:\n")
    print("| frames pruned | tokens kept | test accuracy (mean ± std) | per fold | parameters | multiply-adds |")
    print("|---:|---:|---:|---|---:|---:|")
    b = baked(folds[0] / "model")
    print(f"| 0 % | {b[2]} | {mean_std(before)} | {' / '.join(f'{v:.3f}' for v in before)} | {b[0]:,} | {b[1] / 1e6:.2f} M |")
    by_level = {}
    for level in {int(p.name.split("-p")[1]) for p in frames.glob("fold*-p*") if p.is_dir()}:
        by_level[level] = [r for r in (frames / f"{f.name}-p{level}" for f in folds) if (r / "result.json").exists()]
    # A cross-validation run with --prune-frames alone supplies its own level.
    if pruned:
        spec = json.loads((pruned[0] / "pruned" / "model" / "provenance.json").read_text())["pruning"]
        if spec["channels"] == 0:
            by_level[round(spec["frames"])] = [f / "pruned" for f in pruned]
    for level, runs in sorted(by_level.items()):
        if not runs:
            continue
        acc = [test_accuracy(r) for r in runs]
        s = baked(runs[0] / "model")
        print(f"| {level} % | {s[2]} | {mean_std(acc)} | {' / '.join(f'{v:.3f}' for v in acc)} | {s[0]:,} ({s[0] / b[0]:.0%}) | "
              f"{s[1] / 1e6:.2f} M ({s[1] / b[1]:.0%}) |")


if __name__ == "__main__":
    main()
