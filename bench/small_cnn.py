#!/usr/bin/env python3
"""The anchor a user would write for a camera set: a small CNN trained from scratch in PyTorch on
CPU, on exactly the folds of a `pvt3 cv` run (its recorded splits), so that its figure stands
beside the network's run for run.

    python3 -m venv target/cnn-venv && target/cnn-venv/bin/pip install torch numpy
    target/cnn-venv/bin/python bench/small_cnn.py DATA.npz CV_DIR [--epochs 100] [--patience 20]

DATA.npz is a camera set of `pvt3 import` (uint8 `x` `[N, H, W, C, T]` or `[N, H, W, T]`); a touch's
frames are stacked as input channels (C · T of them; a still image is its colours), each value
standardised by the training touches. Three blocks of 3 × 3 convolutions (32, 64, 128 channels,
batch norm, ReLU; max pooling after the first two, the mean over the image after the last),
dropout 0.3, a linear layer; AdamW (learning rate 1e-3, weight decay 1e-4), batches of 32,
cross-entropy. For each seed and validation fold k of CV_DIR: folds other than k and 4 train, the
epoch that reads fold k best is kept (the first among equals; a run stops once fold k has not
risen for `--patience` epochs), and 4 tests it. No test touch reaches training, the
standardisation or the choice. Each run is seeded by its cross-validation's seed and fold.
"""
import argparse
import sys
import time
from pathlib import Path

import numpy as np
import torch
from torch import nn

sys.path.insert(0, str(Path(__file__).parent))
from camera_linear import TEST_FOLD, runs, summary  # noqa: E402


def network(inputs, classes):
    def block(i, o, pool):
        layers = [nn.Conv2d(i, o, 3, padding=1), nn.BatchNorm2d(o), nn.ReLU()]
        return layers + ([nn.MaxPool2d(2)] if pool else [])

    return nn.Sequential(
        *block(inputs, 32, True),
        *block(32, 64, True),
        *block(64, 128, False),
        nn.AdaptiveAvgPool2d(1),
        nn.Flatten(),
        nn.Dropout(0.3),
        nn.Linear(128, classes),
    )


def accuracy(model, x, y):
    model.eval()
    with torch.no_grad():
        return (model(x).argmax(1) == y).float().mean().item()


def run(x, y, train, val, test, classes, seed, args):
    """The test accuracy of the epoch that reads the validation touches best, and that epoch."""
    torch.manual_seed(seed)
    mu, sd = x[train].mean(0), x[train].std(0).clamp_min(1e-3)
    z = (x - mu) / sd
    xt, yt = z[train], y[train]
    model = network(x.shape[1], classes)
    optimiser = torch.optim.AdamW(model.parameters(), lr=1e-3, weight_decay=1e-4)
    loss = nn.CrossEntropyLoss()
    best, best_epoch, state = -1.0, 0, None
    for epoch in range(1, args.epochs + 1):
        model.train()
        order = torch.randperm(len(xt))
        for i in range(0, len(order), 32):
            batch = order[i : i + 32]
            if len(batch) < 2:
                continue  # batch norm needs two
            optimiser.zero_grad()
            loss(model(xt[batch]), yt[batch]).backward()
            optimiser.step()
        v = accuracy(model, z[val], y[val])
        if v > best:
            best, best_epoch, state = v, epoch, {k: t.clone() for k, t in model.state_dict().items()}
        elif epoch - best_epoch >= args.patience:
            break
    model.load_state_dict(state)
    return accuracy(model, z[test], y[test]), best, best_epoch


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("data")
    parser.add_argument("cv_dir")
    parser.add_argument("--epochs", type=int, default=100)
    parser.add_argument("--patience", type=int, default=20)
    args = parser.parse_args()
    torch.set_num_threads(1)
    data = np.load(args.data)
    x = data["x"]
    if x.ndim == 4:
        x = x[:, :, :, None, :]
    n, h, w, c, t = x.shape
    x = torch.tensor(x.transpose(0, 3, 4, 1, 2).reshape(n, c * t, h, w), dtype=torch.float32)
    y = torch.tensor(data["y"].astype(np.int64))
    classes = int(y.max()) + 1
    results = []
    for seed, k, folds in runs(args.cv_dir):
        train, val, test = (folds != k) & (folds != TEST_FOLD), folds == k, folds == TEST_FOLD
        started = time.time()
        a, v, epoch = run(x, y, torch.tensor(train), torch.tensor(val), torch.tensor(test), classes, seed * 10 + k, args)
        results.append((seed, a))
        print(f"seed {seed} fold {k}: validation {v:.4f} (epoch {epoch}), test {a:.4f}, {time.time() - started:.0f} s", flush=True)
    print(summary(results, "a small CNN"))


if __name__ == "__main__":
    main()
