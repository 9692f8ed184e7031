"""Which test touches the models get wrong, and whether it is the same ones (docs/results.md, "One
file per sensor"): over many runs of the same data set, a touch that nearly every run answers
wrongly caps what any one such model can score, and the runs' probabilities averaged (not one
model, and not allowed as a result: it is here to show how much of the error is the runs'
disagreement) shows how much of it a single run could still win.

    target/onnx-venv/bin/python bench/hard_touches.py runs/cv-anytime-icub/seed*/fold?/pruned ...

Each argument is a run (a `pvt3 cv` run `OUT/seedS/foldK` or its pruned run); its answers on the
test fold (fold 4) at the whole touch come from `pvt3 eval RUN --anytime --answers` (cached in
target/stop_rules/, as bench/stop_rules.py reads them). Runs are grouped by their cross-validation
(and pruned or not); the last line pools every run given. A touch is *hard* when at least
HARD (0.75 by default) of the runs answer it wrongly. Beside each hard touch: the classes of its
three nearest touches outside the test fold by channel levels (each channel's mean over the
window, standardised over those touches), from the data set the first run was trained on: what
the recordings themselves place it among.
"""
import json
import os
import sys
from pathlib import Path

import numpy as np

from stop_rules import answers, cross_validation_of, nearest_by_levels

HARD = float(os.environ.get("HARD", "0.75"))


def group_of(run):
    """A run's cross-validation (and pruned or not), or the run itself outside one."""
    found = cross_validation_of(run)
    if found is None:
        return str(run)
    cv, pruned = found
    return cv.name + (" (pruned)" if pruned else "")


def summary(name, probabilities, labels):
    answered = np.array([p.argmax(1) for p in probabilities])  # [runs, touches]
    wrong = (answered != labels).mean(0)
    accuracies = (answered == labels).mean(1)
    averaged = (np.mean(probabilities, 0).argmax(1) == labels).mean()
    hard = np.flatnonzero(wrong >= HARD)
    print(f"| {name} | {len(probabilities)} | {accuracies.mean():.4f} ± {accuracies.std(ddof=1):.4f} | {accuracies.max():.4f} | "
          f"{len(hard)} | {1 - len(hard) / len(labels):.4f} | {averaged:.4f} |")
    return hard, answered


def main():
    runs = sys.argv[1:]
    if not runs:
        sys.exit(__doc__)
    if len(runs) < 2:
        sys.exit("give at least two runs: a touch is hard by how many of them answer it wrongly")
    groups, labels = {}, None
    for run in runs:
        p, y, _ = answers(run, 4)
        if labels is not None and not np.array_equal(labels, y):
            sys.exit(f"{run}: its test fold is not the other runs' (another data set?)")
        labels = y
        groups.setdefault(group_of(run), []).append(p[:, -1, :])
    print(f"| runs of | runs | test accuracy, mean ± std | best run | touches wrong in ≥ {HARD:.0%} of the runs | "
          "at most, with those wrong | the runs' probabilities averaged (not a model) |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for name, probabilities in groups.items():
        summary(name, probabilities, labels)
    everything = [p for probabilities in groups.values() for p in probabilities]
    hard, answered = summary("all of the above", everything, labels)
    data = json.loads(Path(runs[0], "model", "provenance.json").read_text())["data"]
    print(f"\nhard touches of all the runs (test-fold index: class → the answer most runs give, "
          f"share of the runs wrong; the classes of its 3 nearest non-test touches in {data} by channel levels):")
    if len(hard) == 0:
        print("  none")
    for i, near in zip(hard, nearest_by_levels(data, hard)):
        wrong = answered[:, i][answered[:, i] != labels[i]]
        answer = np.bincount(wrong).argmax()
        print(f"  {i}: {labels[i]} → {answer}, {len(wrong) / len(answered):.0%}; nearest: {', '.join(map(str, near))}")


if __name__ == "__main__":
    main()
