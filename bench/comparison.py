"""The comparison tables of docs/results.md: one row per model, each a cross-validation of several
seeds × 4 folds (`bash bench/baselines.sh`), read from its `cv.json` as `pvt3 cv` wrote it: the
mean ± std of all runs, each seed's mean, and the 95 % interval of the mean (Student's t over the
seed means), with the model's size and the paper's figure beside it.

    python3 bench/comparison.py                             # the two tables of docs/results.md
    python3 bench/comparison.py tried                       # its "Pushing accuracy" tables
    python3 bench/comparison.py joint                       # its "Joint learning" table
    python3 bench/comparison.py 'LABEL|PUBLISHED|DIR[:pruned]' ...   # one table of your own rows

DIR is a `pvt3 cv` output directory; `:pruned` reads its pruned and fine-tuned runs, `:partner`
and `:partner-pruned` a joint cross-validation's other sensor's (`--joint`). Sizes come
from `pvt3 info` of its first run: the baked (deployed) size for a pruned PVT³ model, the
trainable parameters otherwise (random pruning leaves the matrices dense). A row whose cross-validation has not run says which command
runs it.
"""
import json
import re
import subprocess
import sys
from pathlib import Path

PVT3 = "./target/release/pvt3"


def size(run):
    out = subprocess.run([PVT3, "info", str(run)], capture_output=True, text=True, check=True).stdout
    provenance = json.loads((run / "model" / "provenance.json").read_text())
    baked = re.search(r"after baking\s+(\d+) parameters, (\d+) multiply-adds per sample", out)
    pruning = provenance.get("pruning") or {}
    if (pruning.get("channels") or pruning.get("frames")) and baked:
        return int(baked[1]), int(baked[2])
    return int(re.search(r"parameters\s+(\d+) trainable", out)[1]), int(re.search(r"mult-adds\s+(\d+) per sample", out)[1])


def cv_part(where):
    """`DIR` or `DIR:pruned` (a `pvt3 cv` directory, its pruned runs with `:pruned`; a joint one's
    other sensor with `:partner` and `:partner-pruned`): that part of its cv.json under plain keys (runs, mean, std, seed_means, interval) and the first run's
    directory, or None if the directory has no cv.json yet."""
    directory, _, part = where.partition(":")
    summary_path = Path(directory) / "cv.json"
    if not summary_path.exists():
        return None
    s = json.loads(summary_path.read_text())
    first = s["runs"][0]
    run = Path(directory) / f"seed{first['seed']}" / f"fold{first['val_fold']}"
    if part.startswith("partner"):
        # A joint cross-validation's other sensor: its summary inside, its runs inside each run.
        s, run, part = s["partner"], run / "partner", part.removeprefix("partner").removeprefix("-")
    key = "pruned_" if part == "pruned" else ""
    if part == "pruned":
        run = run / "pruned"
    return dict(runs=s[f"{key}runs"], mean=s[f"{key}mean_test_accuracy"], std=s[f"{key}std_test_accuracy"],
                seed_means=s.get(f"{key}seed_means", []), interval=s.get(f"{key}ci95_test_accuracy"), run=run)


def row(spec):
    label, published, where = spec.split("|")
    part = cv_part(where)
    if part is None:
        directory = where.partition(":")[0]
        name = Path(directory).name.removeprefix("cv-")
        name = re.sub(r"^unpruned-(\w+)-.*", r"unpruned-prunings-\1", re.sub(r"^masks-(\w+)-.*", r"prunings-\1", name))
        return f"| {label} | | | not run yet (`bash bench/baselines.sh {name}`) | | | | {published} |"
    runs, mean, std, seed_means, interval, run = (part[k] for k in ("runs", "mean", "std", "seed_means", "interval", "run"))
    params, macs = size(run)
    seeds = len({r["seed"] for r in runs})
    # Means of a few accuracies often end in a 5 at the fifth decimal: round it up, as `pvt3 cv` prints.
    mean += 1e-12
    means = ", ".join(f"{m:.4f}" for m in seed_means)
    ci = f"[{interval[0]:.4f}, {interval[1]:.4f}]" if interval else "—"
    return (f"| {label} | {params:,} | {macs / 1e6:.2f} M | {seeds} × {len(runs) // max(seeds, 1)} "
            f"| **{mean:.4f} ± {std:.4f}** | {means} | {ci} | {published} |")


# The rows of docs/results.md. Published: the PVT³ report's Table 1 (ViViT unpruned, PVT³ with
# random pruning; RAEC trained on one sensor, "independent", as here, with the joint-learning
# figure beside it) and, for ViT, the best validation accuracy of its learning curves (the report
# gives no ViT test figure).
TABLES = {
    "iCub-20": [
        "ViT|0.8884 (validation)|runs/cv-vit-icub",
        "RAEC|0.9114 (joint: 0.9323)|runs/cv-raec-icub",
        "PVT³ unpruned (the ViViT backbone, masks untrained)|0.9224|runs/cv-rpp-icub",
        "PVT³ pruned: 60 % of channels, from the unpruned runs (masks trained without L1)|—|runs/cv-unpruned-icub-channels60:pruned",
        "PVT³, trained masks, unpruned|—|runs/cv-masks-icub",
        "PVT³ pruned: 50 % of channels|—|runs/cv-masks-icub-channels50:pruned",
        "PVT³ pruned: 60 % of channels|—|runs/cv-masks-icub-channels60:pruned",
        "PVT³ pruned: 50 % of frames|—|runs/cv-masks-icub:pruned",
        "PVT³ pruned: 50 % of channels and 50 % of frames|—|runs/cv-masks-icub-channels50-frames50:pruned",
        "PVT³, persistent random pruning 20 %|0.9425|runs/cv-rpp-icub:pruned",
        "PVT³, per-step random pruning 5 %|0.9425|runs/cv-rp-icub",
    ],
    "BioTac-20": [
        "ViT|0.9777 (validation)|runs/cv-vit-biotac",
        "RAEC|0.9531 (joint: 0.9601)|runs/cv-raec-biotac",
        "PVT³ unpruned (the ViViT backbone, masks untrained)|0.9659|runs/cv-rpp-biotac",
        "PVT³ pruned: 60 % of channels, from the unpruned runs (masks trained without L1)|—|runs/cv-unpruned-biotac-channels60:pruned",
        "PVT³, trained masks, unpruned|—|runs/cv-masks-biotac",
        "PVT³ pruned: 50 % of channels|—|runs/cv-masks-biotac-channels50:pruned",
        "PVT³ pruned: 60 % of channels|—|runs/cv-masks-biotac-channels60:pruned",
        "PVT³ pruned: 50 % of frames|—|runs/cv-masks-biotac:pruned",
        "PVT³ pruned: 50 % of channels and 50 % of frames|—|runs/cv-masks-biotac-channels50-frames50:pruned",
        "PVT³, persistent random pruning 20 %|0.9798|runs/cv-rpp-biotac:pruned",
        "PVT³, per-step random pruning 5 %|0.9798|runs/cv-rp-biotac",
    ],
}


def unpruned_and_pruned(label, directory):
    """The two rows of a tried change: its unpruned runs and their pruning to 60 % of channels."""
    return [f"{label}, unpruned|—|{directory}", f"{label}, pruned to 60 % of channels|—|{directory}:pruned"]


# The rows of docs/results.md's "Pushing accuracy": each change beside the rows it starts from.
TRIED = {
    "iCub-20, masks trained without L1 (the trainer's defaults), pruned to 60 % of channels": [
        "100 epochs (the headline rows), unpruned|—|runs/cv-rpp-icub",
        "100 epochs, pruned to 60 % of channels|—|runs/cv-unpruned-icub-channels60:pruned",
        *unpruned_and_pruned("300 epochs", "runs/cv-e300-icub"),
        *unpruned_and_pruned("mixup 0.2", "runs/cv-mixup-icub"),
        *unpruned_and_pruned("same-class extrapolation, `--extrapolate 1`", "runs/cv-extrapolate-icub"),
        *unpruned_and_pruned("its levels only, `--extrapolate 1 --extrapolate-levels`", "runs/cv-extrapolate-levels-icub"),
    ],
    "BioTac-20, trained masks (`--l1 0.25 --mask-lr 10`), pruned to 60 % of channels": [
        "as in the headline rows, unpruned|—|runs/cv-masks-biotac",
        "as in the headline rows, pruned to 60 % of channels|—|runs/cv-masks-biotac-channels60:pruned",
        *unpruned_and_pruned("EMA 0.995", "runs/cv-ema-biotac"),
        *unpruned_and_pruned("mixup 0.2", "runs/cv-mixup-biotac"),
        *unpruned_and_pruned("same-class extrapolation, `--extrapolate 1`", "runs/cv-extrapolate-biotac"),
        *unpruned_and_pruned("its levels only, `--extrapolate 1 --extrapolate-levels`", "runs/cv-extrapolate-levels-biotac"),
        *unpruned_and_pruned("time shift ±20 frames", "runs/cv-shift-biotac"),
        *unpruned_and_pruned("300 epochs with mixup 0.2", "runs/cv-e300-mixup-biotac"),
        *unpruned_and_pruned("300 epochs with mixup 0.4", "runs/cv-e300-mixup0.4-biotac"),
        "300 epochs with mixup 0.2, pruned to 60 % of channels, 100 epochs of fine-tuning|—|runs/cv-e300-mixup-biotac-channels60-ft100:pruned",
        "300 epochs with mixup 0.2, pruned to 70 % of channels|—|runs/cv-e300-mixup-biotac-channels70:pruned",
        *unpruned_and_pruned("spectral head of 16 bands", "runs/cv-spectral-biotac"),
        "spectral head of 16 bands, pruned to 70 % of channels|—|runs/cv-spectral-biotac-channels70:pruned",
        "spectral head of 16 bands, pruned to 50 % of channels and 50 % of frames|—|runs/cv-spectral-biotac-channels50-frames50:pruned",
    ],
}


# docs/results.md's "Joint learning": each sensor's network of a joint cross-validation, tested on
# its own sensor, beside the same network trained alone. Published: RAEC trained jointly (Gao et al.).
JOINT = {
    "iCub-20": [
        "alone (the headline rows), unpruned|—|runs/cv-rpp-icub",
        "alone, pruned to 60 % of channels|—|runs/cv-unpruned-icub-channels60:pruned",
        "joint, encodings pulled together (Gao et al.), unpruned|0.9323 (RAEC)|runs/cv-joint-icub",
        "joint, encodings pulled together, pruned to 60 % of channels|—|runs/cv-joint-icub:pruned",
        "joint, one temporal transformer, unpruned|—|runs/cv-joint-shared-icub",
        "joint, one temporal transformer, pruned to 60 % of channels|—|runs/cv-joint-shared-icub:pruned",
    ],
    "BioTac-20": [
        "alone (the headline rows), unpruned|—|runs/cv-rpp-biotac",
        "alone, pruned to 60 % of channels|—|runs/cv-unpruned-biotac-channels60:pruned",
        "joint, encodings pulled together (Gao et al.), unpruned|0.9601 (RAEC)|runs/cv-joint-icub:partner",
        "joint, encodings pulled together, pruned to 60 % of channels|—|runs/cv-joint-icub:partner-pruned",
        "joint, one temporal transformer, unpruned|—|runs/cv-joint-shared-icub:partner",
        "joint, one temporal transformer, pruned to 60 % of channels|—|runs/cv-joint-shared-icub:partner-pruned",
    ],
}


def table(specs):
    print("| model | parameters | multiply-adds | seeds × folds | test accuracy, mean ± std | seed means | 95 % interval | published |")
    print("|---|---:|---:|---|---:|---|---|---:|")
    for spec in specs:
        print(row(spec))


def main():
    named = {"tried": TRIED, "joint": JOINT}
    if sys.argv[1:] and sys.argv[1] not in named:
        table(sys.argv[1:])
        return
    for name, specs in (named[sys.argv[1]] if sys.argv[1:] else TABLES).items():
        print(f"### {name}\n")
        table(specs)
        print()


if __name__ == "__main__":
    main()
