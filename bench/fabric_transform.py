#!/usr/bin/env python3
"""Readings transformed per touch, to see whether a touch at an unseen force looks like a trained
one (docs/robustness.md, "Tried for unseen forces"). Reads an imported FabricSlide set (`pvt3
import ... --columns 'channel*'`, the 16 capacitive channels) and writes the same set with each
touch's readings transformed, for `bench/robustness.sh` to train on:

    python3 bench/fabric_transform.py KIND [SOURCE.npz]   # → target/robustness/KIND/fabric.npz
    FOLDS=0 VARIANT=KIND bash bench/robustness.sh FABRICSLIDE forces-unseen

KIND, per touch x[channel, frame] over its own frames:
  framenorm  each frame divided by its mean over the channels (the pattern, not the press)
  logframe   log(1 + x), minus its mean over the channels in each frame
  dc         each channel minus its mean over the touch (the variation only)
  ema        each channel minus its running mean (weight 1/16 a frame; causal, so it could stream)
  diff       each channel's change from the previous frame

Needs numpy (the test venv has it: target/onnx-venv/bin/python).
"""
import os
import sys

import numpy as np


def transform(a, kind):
    """One touch, channels × frames."""
    if kind == "framenorm":
        return a / a.mean(0, keepdims=True)
    if kind == "logframe":
        la = np.log(a + 1)
        return la - la.mean(0, keepdims=True)
    if kind == "dc":
        return a - a.mean(1, keepdims=True)
    if kind == "ema":
        out, m = np.empty_like(a), a[:, 0].copy()
        for t in range(a.shape[1]):
            m += (a[:, t] - m) / 16
            out[:, t] = a[:, t] - m
        return out
    if kind == "diff":
        return np.diff(a, axis=1, prepend=a[:, :1])
    sys.exit(f"unknown KIND {kind}: framenorm, logframe, dc, ema or diff")


def main():
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    kind = sys.argv[1]
    root = os.path.join(os.path.dirname(__file__), "..")
    source = sys.argv[2] if len(sys.argv) == 3 else os.path.join(root, "target/robustness/capacitive/fabric.npz")
    data = dict(np.load(source))
    x, lengths = data["x"].astype(np.float64), data["lengths"]
    out = np.zeros_like(x)
    for i, n in enumerate(lengths):
        out[i, :, :n] = transform(x[i, :, :n], kind)
    data["x"] = out.astype(np.float32)
    folder = os.path.join(root, "target/robustness", kind)
    os.makedirs(folder, exist_ok=True)
    np.savez(os.path.join(folder, "fabric.npz"), **data)
    print(f"{kind}: {len(lengths)} touches from {source} into {folder}/fabric.npz")


if __name__ == "__main__":
    main()
