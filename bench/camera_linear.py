#!/usr/bin/env python3
"""The linear anchor for camera touches (docs/camera.md): a ridge classifier on simple per-touch
image statistics, trained on exactly the folds of a `pvt3 cv` run, so that its figure stands
beside the network's run for run.

    target/onnx-venv/bin/python bench/camera_linear.py DATA.npz CV_DIR [--grid HxW]   # needs numpy

DATA.npz is a camera set of `pvt3 import` (uint8 `x` `[N, H, W, C, T]` or `[N, H, W, T]`, with
`background` where imported with `--subtract-first`); CV_DIR the `pvt3 cv --data DATA.npz` run
whose recorded splits (`seed*/fold*/model/provenance.json`, `trained_on.folds`) it follows. For
each seed and validation fold k: folds other than k and 4 train, k chooses the ridge's strength,
4 tests. No test touch reaches the features' standardisation or the choice.

Features of a touch (its frames minus its background, if it has one), each from all its frames:
- `mean`: the mean image, shrunk to 6 × 8 (or `--grid HxW`) by area averaging, every colour;
- `motion`: the mean absolute change from frame to frame, shrunk likewise;
- `colour`: each colour's mean, standard deviation and 10th, 50th and 90th percentiles.
"""
import json
import statistics
import sys
from pathlib import Path

import numpy as np

GRID = (6, 8)
STRENGTHS = [1e-3, 1e-2, 1e-1, 1.0, 10.0]
TEST_FOLD = 4


def shrink(image, grid):
    """Area average of `image` `[H, W, C]` to `grid` (the remainder of rows and columns dropped)."""
    h, w = grid
    rows, cols = image.shape[0] // h, image.shape[1] // w
    cut = image[: rows * h, : cols * w]
    return cut.reshape(h, rows, w, cols, -1).mean((1, 3))


def features(touch, background, grid):
    """One touch `[H, W, C, T]` as float, minus its background `[H, W, C]`."""
    frames = touch.astype(np.float32)
    if background is not None:
        frames -= background.astype(np.float32)[..., None]
    mean = shrink(frames.mean(-1), grid).ravel()
    # A still image (one frame) has no motion: zeros, which the standardisation leaves at 0.
    change = np.abs(np.diff(frames, axis=-1)).mean(-1) if frames.shape[-1] > 1 else np.zeros(frames.shape[:-1])
    motion = shrink(change, grid).ravel()
    per_colour = frames.reshape(-1, frames.shape[2], frames.shape[3]).transpose(1, 0, 2).reshape(frames.shape[2], -1)
    colour = np.concatenate([per_colour.mean(1), per_colour.std(1), *np.percentile(per_colour, [10, 50, 90], axis=1)])
    return np.concatenate([mean, motion, colour])


def load(path, grid):
    data = np.load(path)
    x, y = data["x"], data["y"].astype(int)
    if x.ndim == 4:
        x = x[:, :, :, None, :]
    background = data["background"] if "background" in data.files else None
    if background is not None and background.ndim == 3:
        background = background[..., None]
    table = np.stack([features(x[i], None if background is None else background[i], grid) for i in range(len(x))])
    return table, y


def ridge(train, labels, test, classes, strength):
    """Predictions of a ridge classifier on features standardised by the training touches."""
    mu, sd = train.mean(0), train.std(0) + 1e-9
    a, b = (train - mu) / sd, (test - mu) / sd
    a, b = np.c_[a, np.ones(len(a))], np.c_[b, np.ones(len(b))]
    targets = np.eye(classes)[labels] * 2 - 1
    w = np.linalg.solve(a.T @ a + strength * len(a) * np.eye(a.shape[1]), a.T @ targets)
    return (b @ w).argmax(1)


def t_975(df):
    """Student's t quantile, as bench/robustness_report.py and `pvt3 cv` take it."""
    sys.path.insert(0, str(Path(__file__).parent))
    from robustness_report import t_975 as t

    return t(df)


def summary(results, what):
    """The line of a script's runs `results` ((seed, test accuracy) each, of `what`): the mean
    ± std and, over several seeds, their means and the 95 % interval (Student's t over them)."""
    accuracies = [a for _, a in results]
    line = f"{len(results)} runs ({what}): test {statistics.mean(accuracies):.4f}"
    if len(accuracies) > 1:
        line += f" ± {statistics.stdev(accuracies):.4f}"
    seeds = sorted({s for s, _ in results})
    if len(seeds) > 1:
        means = [statistics.mean(a for s, a in results if s == seed) for seed in seeds]
        half = t_975(len(means) - 1) * statistics.stdev(means) / len(means) ** 0.5
        m = statistics.mean(means)
        line += f"; seed means {', '.join(f'{v:.4f}' for v in means)}, 95 % interval [{m - half:.4f}, {m + half:.4f}]"
    return line


def runs(cv_dir):
    """(seed, validation fold, folds) of each run of a `pvt3 cv` directory, from what it recorded."""
    found = []
    for provenance in sorted(Path(cv_dir).glob("seed*/fold*/model/provenance.json")):
        p = json.loads(provenance.read_text())
        folds = np.array([int(f) for f in p["trained_on"]["folds"]])
        found.append((p["seed"], p["val_fold"], folds))
    if not found:
        sys.exit(f"{cv_dir}: no seed*/fold*/model/provenance.json (a finished `pvt3 cv` directory)")
    return found


def main():
    args = sys.argv[1:]
    grid = GRID
    if len(args) == 4 and args[2] == "--grid":
        grid = tuple(int(v) for v in args[3].split("x"))
        args = args[:2]
    if len(args) != 2:
        sys.exit(__doc__)
    table, labels = load(args[0], grid)
    classes = labels.max() + 1
    results = []
    for seed, k, folds in runs(args[1]):
        train, val, test = (folds != k) & (folds != TEST_FOLD), folds == k, folds == TEST_FOLD
        scores = [(ridge(table[train], labels[train], table[val], classes, s) == labels[val]).mean() for s in STRENGTHS]
        best = STRENGTHS[int(np.argmax(scores))]
        accuracy = (ridge(table[train], labels[train], table[test], classes, best) == labels[test]).mean()
        results.append((seed, accuracy))
        print(f"seed {seed} fold {k}: validation {max(scores):.4f} (strength {best}), test {accuracy:.4f}")
    print(summary(results, f"{table.shape[1]} features"))


if __name__ == "__main__":
    main()
