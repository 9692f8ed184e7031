#!/usr/bin/env python3
"""A linear look at what carries over to an unseen pressing force on FabricSlide
(docs/robustness.md, "Tried for unseen forces"). Per touch, features of its middle 140 rows of the
16 capacitive channels; each feature set is classified by a ridge classifier and by one nearest
neighbour (both on standardised features), trained on forces 120–180 and tested on 210 and 250;
trained on forces 150–250 and tested on 120 (a lighter press); trained on speeds 20–120 mm/s and
tested on 10 and 150 (both directions); trained on the negative speeds and tested on the positive
ones (the other sliding direction, docs/robustness.md "Robust by default"); and, for comparison,
on a random quarter of the touches held out. Then each fabric's channel levels against the force:
a straight line through its levels at 120, 150 and 180, and how far it misses the levels at each
force, beside the spread of the levels across its touches at one force. Last, each fabric's
vibration at each force and sliding direction: its touches' `spread`, the mean over channels.

    target/onnx-venv/bin/python bench/fabric_linear.py FABRICSLIDE   # needs numpy

Feature sets: `level` (each channel's mean), `pattern` (the levels over their mean), `spread`
(log of each channel's standard deviation), `bands` (log power of 13 bands of 5 frequencies from 1,
each channel), `relative-bands` (the same minus each channel's mean over bands).
"""
import re
import sys
from pathlib import Path

import numpy as np

NAME = re.compile(r"(\w+?)_F(\d+)_V(-?\d+)mmps_\d+\.csv")
MIDDLE = 140


def features(a, kind):
    """One touch, frames × channels."""
    if kind == "level":
        return a.mean(0)
    if kind == "pattern":
        return a.mean(0) / a.mean()
    if kind == "spread":
        return np.log(a.std(0) + 1e-3)
    power = np.abs(np.fft.rfft(a - a.mean(0), axis=0)) ** 2
    bands = np.log(np.array([power[i : i + 5].sum(0) for i in range(1, 66, 5)]) + 1e-3)
    return (bands if kind == "bands" else bands - bands.mean(0)).ravel()


def standardised(train, test):
    mu, sd = train.mean(0), train.std(0) + 1e-9
    return (train - mu) / sd, (test - mu) / sd


def ridge(train, labels, test, classes, lam=0.1):
    a, b = standardised(train, test)
    a, b = np.c_[a, np.ones(len(a))], np.c_[b, np.ones(len(b))]
    targets = np.eye(classes)[labels] * 2 - 1
    w = np.linalg.solve(a.T @ a + lam * len(a) * np.eye(a.shape[1]), a.T @ targets)
    return (b @ w).argmax(1)


def nearest(train, labels, test, _classes):
    a, b = standardised(train, test)
    return labels[((b[:, None] - a[None]) ** 2).sum(-1).argmin(1)]


def main():
    folder = Path(sys.argv[1] if len(sys.argv) > 1 else "FabricSlide") / "data" / "fabric"
    touches, labels, forces, speeds, names = [], [], [], [], {}
    for path in sorted(folder.glob("*.csv")):
        m = NAME.fullmatch(path.name)
        if not m:
            continue
        a = np.loadtxt(path, delimiter=",", skiprows=1)[:, 3:]
        start = (len(a) - MIDDLE) // 2
        touches.append(a[start : start + MIDDLE])
        labels.append(names.setdefault(m[1], len(names)))
        forces.append(int(m[2]))
        speeds.append(int(m[3]))
    if not touches:
        sys.exit(f"{folder}: no FabricSlide touches")
    labels, forces, speeds = np.array(labels), np.array(forces), np.array(speeds)
    held = np.random.default_rng(0).random(len(labels)) < 0.25
    beyond = np.isin(abs(speeds), [10, 150])
    splits = [(forces <= 180, forces >= 210), (forces > 120, forces == 120), (~beyond, beyond), (speeds < 0, speeds > 0), (~held, held)]
    print(
        "| features | classifier | unseen forces (210, 250) | force 120 | speeds 10, 150 | other direction | random quarter |\n"
        "|---|---|---:|---:|---:|---:|---:|"
    )
    for kind in ["level", "pattern", "spread", "bands", "relative-bands"]:
        x = np.array([features(a, kind) for a in touches])
        for name, fit in [("ridge", ridge), ("1-NN", nearest)]:
            acc = [(fit(x[a], labels[a], x[b], len(names)) == labels[b]).mean() for a, b in splits]
            print(f"| {kind} | {name} | " + " | ".join(f"{v:.3f}" for v in acc) + " |")
    levels = np.array([a.mean(0) for a in touches])
    print("\n| fabric | force | line's miss (mean over channels) | spread of levels across touches |\n|---|---:|---:|---:|")
    for fabric, c in names.items():
        at = sorted({f for f in forces[labels == c]})
        mean = {f: levels[(labels == c) & (forces == f)].mean(0) for f in at}
        fit_at = [f for f in at if f <= 180]
        coef = np.linalg.lstsq(np.c_[np.ones(len(fit_at)), fit_at], np.array([mean[f] for f in fit_at]), rcond=None)[0]
        for f in at:
            miss = np.abs(coef[0] + coef[1] * f - mean[f]).mean()
            spread = levels[(labels == c) & (forces == f)].std(0).mean()
            print(f"| {fabric} | {f} | {miss:.1f} | {spread:.1f} |")
    vibration(touches, labels, forces, speeds, names)


def vibration(touches, labels, forces, speeds, names):
    """Each fabric's mean `spread` (log standard deviation, over channels and touches) at each
    force, negative and positive speeds apart: how much it vibrates under each press."""
    spread = np.array([features(a, "spread").mean() for a in touches])
    levels = sorted(set(forces))
    print("\n| fabric | speeds | " + " | ".join(f"force {f}" for f in levels) + " |")
    print("|---|---|" + "---:|" * len(levels))
    for fabric, c in names.items():
        for sign, side in [(-1, "negative"), (1, "positive")]:
            at = [(labels == c) & (forces == f) & (np.sign(speeds) == sign) for f in levels]
            if any(m.any() for m in at):
                print(f"| {fabric} | {side} | " + " | ".join(f"{spread[m].mean():.2f}" if m.any() else "—" for m in at) + " |")


if __name__ == "__main__":
    main()
