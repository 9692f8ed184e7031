#!/usr/bin/env python3
"""The simplest anchor a user tries on a camera set: a ridge classifier on the raw values of a
touch (every pixel of every frame, at the size `pvt3 import` stored), each value standardised by
the training touches, its strength chosen on the validation fold; trained on exactly the folds of
a `pvt3 cv` run (its recorded splits), so that its figure stands beside the network's run for run.

    target/onnx-venv/bin/python bench/pixel_ridge.py DATA.npz CV_DIR   # needs numpy

For each seed and validation fold k of CV_DIR: folds other than k and 4 train, k chooses the
strength, 4 tests; no test touch reaches the standardisation or the choice. Targets are ±1 (+1
for a touch's class), rows and targets centred; the system solved is the rows' (the dual), as
touches are far fewer than values.
"""
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from camera_linear import TEST_FOLD, runs, summary  # noqa: E402

STRENGTHS = [1e-4, 1e-3, 1e-2, 1e-1, 1.0, 10.0, 100.0, 1000.0]


def fit(train, labels, classes, strengths):
    """Ridge weights (values × classes) and biases for each strength, by the dual system."""
    mu, sd = train.mean(0), train.std(0)
    sd[sd < 1e-3] = 1e-3
    x = (train - mu) / sd
    mean = x.mean(0)
    x = x - mean
    targets = np.eye(classes)[labels] * 2 - 1
    t_mean = targets.mean(0)
    gram = x @ x.T
    fits = []
    for s in strengths:
        alpha = np.linalg.solve(gram + s * len(x) * np.eye(len(x)), targets - t_mean)
        w = x.T @ alpha
        fits.append((w, t_mean - mean @ w))
    return lambda rows, i: (((rows - mu) / sd) @ fits[i][0] + fits[i][1]).argmax(1)


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    data = np.load(sys.argv[1])
    table, labels = data["x"].reshape(len(data["x"]), -1).astype(np.float64), data["y"].astype(int)
    classes = labels.max() + 1
    results = []
    for seed, k, folds in runs(sys.argv[2]):
        train, val, test = (folds != k) & (folds != TEST_FOLD), folds == k, folds == TEST_FOLD
        predict = fit(table[train], labels[train], classes, STRENGTHS)
        scores = [(predict(table[val], i) == labels[val]).mean() for i in range(len(STRENGTHS))]
        best = int(np.argmax(scores))
        accuracy = (predict(table[test], best) == labels[test]).mean()
        results.append((seed, accuracy))
        print(f"seed {seed} fold {k}: validation {max(scores):.4f} (strength {STRENGTHS[best]}), test {accuracy:.4f}")
    print(summary(results, f"{table.shape[1]} values a touch"))


if __name__ == "__main__":
    main()
