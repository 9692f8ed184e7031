"""Where the BioTac texture information lives: ridge-regression classifiers on simple features.

    target/bench-venv/bin/python bench/biotac_linear_probe.py     # needs numpy only

Trains on folds 1–3 of data/biotac20.npz and prints the accuracy on the test fold (4) for the
per-electrode mean level, standard deviation, standard deviation of the first difference, all three,
and the log magnitude spectrum (bins 1–40) of the per-sample detrended signal.
"""

import numpy as np

data = np.load("data/biotac20.npz")
x, y, fold = data["x"].astype(np.float64), data["y"], data["fold"]
train, test = (fold != 0) & (fold != 4), fold == 4


def ridge_accuracy(features, lam):
    mu, sd = features[train].mean(0), features[train].std(0) + 1e-9
    g = np.hstack([(features - mu) / sd, np.ones((len(features), 1))])
    targets = np.eye(20)[y]
    w = np.linalg.solve(g[train].T @ g[train] + lam * train.sum() * np.eye(g.shape[1]), g[train].T @ targets[train])
    return ((g[test] @ w).argmax(1) == y[test]).mean()


level, spread, rough = x.mean(2), x.std(2), np.diff(x, axis=2).std(2)
spectrum = np.log1p(np.abs(np.fft.rfft(x - x.mean(2, keepdims=True), axis=2))[:, :, 1:41]).reshape(len(x), -1)
for name, features, lam in [
    ("mean level per electrode", level, 1e-2),
    ("standard deviation over time", spread, 1e-2),
    ("standard deviation of the first difference", rough, 1e-2),
    ("all three", np.hstack([level, spread, rough]), 1e-2),
    ("log spectrum of the detrended signal (bins 1-40)", spectrum, 1e-1),
]:
    print(f"{ridge_accuracy(features, lam):.3f}  {name}")
