#!/usr/bin/env python3
"""Which position-free features of a camera's frames read its objects (docs/camera.md, "The
press's histogram"): the camera spectral head's features alone, as families added one at a time,
each fitted as the trainer fits the head (a multinomial logistic regression by Nesterov's
accelerated gradient, 600 passes, the penalty its validation fold reads best) on exactly the
folds of a `pvt3 cv` run.

    target/onnx-venv/bin/python bench/camera_features.py DATA.npz CV_DIR [FAMILY ...] [--rings N] [--bins N] [--only SEED:FOLD,...]   # needs numpy

FAMILY is one of the rows below (all of them if none is given):
- `rings`: each colour's level and the log mean power of 12 rings of spatial frequency, the
  trainer's head without a histogram, fitted to one row a touch (its frames' mean);
- `rings-frames`: the same features, every frame of a training touch a row of the fit;
- `histogram`: the rings and a hard histogram of each colour's normalised values (24 bins over
  ±3), one row a touch;
- `histogram-frames`: the same, every frame a row;
- `soft-frames`: soft bins (the trainer's, `pvt3_spec::spectrum::space::share_above`), every
  frame a row: the camera layout's default;
- `logs-frames`: `soft-frames` with a touch read as the mean of its frames' features, each
  frame's log ring powers averaged instead of the log of their mean power: the head of `--set
  spectral_log_frames=true`;
- `gradients-frames`: and soft histograms of each colour's differences between neighbouring
  values across and down (`pvt3_spec::spectrum::space::Histogram`), every frame a row: the head
  of `--set spectral_gradients=true`.

`--rings N` and `--bins N` (12 and 24, the camera layout's `spectral_bands` and
`spectral_histogram`) change the head's rings and histogram bins; `--only 0:0,1:1` reads those
runs (seed:validation fold) alone.

The values are normalised pixel by pixel by the training touches of each run (mean and standard
deviation over their frames), as `pvt3 cv` normalises; a touch is read, as the head reads it
whole, by the mean of its frames' levels, powers and histograms (by the mean of their rows, in
`logs-frames`). No test touch reaches the
normalisation, the standardisation, the fit or the choice of penalty.
"""
import argparse
import statistics
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from camera_linear import TEST_FOLD, runs, t_975  # noqa: E402

LAYOUT = (12, 24)  # the camera layout's spectral_bands and spectral_histogram
(RINGS, BINS), RANGE = LAYOUT, 3.0
PENALTIES = [1e-1, 3e-2, 1e-2, 3e-3, 1e-3, 3e-4]
FAMILIES = ["rings", "rings-frames", "histogram", "histogram-frames", "soft-frames", "logs-frames", "gradients-frames"]


def ring_of(h, w, bands):
    """The ring of each frequency of the one-sided transform `[h, w // 2 + 1]`, -1 for zero
    (pvt3_spec::spectrum::space::band_of)."""
    fy = np.where(np.arange(h) <= h // 2, np.arange(h), np.arange(h) - h) / h
    radius = np.sqrt(fy[:, None] ** 2 + (np.arange(w // 2 + 1) / w)[None, :] ** 2)
    low = 1.0 / max(h, w)
    edges = low * (radius.max() / low) ** (np.arange(bands + 1) / bands)
    ring = np.clip(np.searchsorted(edges, radius * (1 + 1e-12), side="right") - 1, 0, bands - 1)
    ring[radius < low * (1 - 1e-9)] = -1
    return ring


def soft_histogram(values):
    """Soft histograms `[T, C, BINS]` of values `[T, C, n]` (pvt3_spec::spectrum::space::share_above)."""
    t, c = values.shape[:2]
    width = 2 * RANGE / BINS
    edges = -RANGE + width * np.arange(1, BINS)
    above = np.clip((values[..., None, :] - edges[:, None]) / width + 0.5, 0, 1).mean(-1)
    cumulative = np.concatenate([np.ones((t, c, 1)), above, np.zeros((t, c, 1))], -1)
    return cumulative[..., :-1] - cumulative[..., 1:]


def per_frame(v, ring, soft, gradients=False):
    """Levels `[T, C]`, ring powers `[T, C, RINGS]` and histograms `[T, C, BINS]` (`[T, C, 3 ·
    BINS]` with the gradients') of one touch's normalised frames `v` `[T, C, H, W]`."""
    t, c = v.shape[:2]
    power = np.abs(np.fft.rfft2(v, norm="ortho")) ** 2
    rings = np.stack([power[..., ring == j].mean(-1) for j in range(RINGS)], -1)
    pixels = v.reshape(t, c, -1)
    if soft:
        histogram = soft_histogram(pixels)
    else:
        width = 2 * RANGE / BINS
        index = np.clip(((pixels + RANGE) / width).astype(int), 0, BINS - 1)
        histogram = np.stack([(index == j).mean(-1) for j in range(BINS)], -1)
    if gradients:
        across = (v[..., :, 1:] - v[..., :, :-1]).reshape(t, c, -1)
        down = (v[..., 1:, :] - v[..., :-1, :]).reshape(t, c, -1)
        histogram = np.concatenate([histogram, soft_histogram(across), soft_histogram(down)], -1)
    return pixels.mean(-1), rings, histogram


def logistic(x, y, classes, penalty, steps=600):
    """The trainer's fit (trainer/src/spectrum_fit/logistic.rs): weights and biases."""
    n, f = x.shape
    step = 1.0 / (0.5 * (1 + (x**2).sum(1)).mean() + penalty)
    targets = np.eye(classes)[y]
    w, b = np.zeros((classes, f)), np.zeros(classes)
    w_before, b_before = w, b
    for k in range(steps):
        m = k / (k + 3)
        wa, ba = w + m * (w - w_before), b + m * (b - b_before)
        s = x @ wa.T + ba
        p = np.exp(s - s.max(1, keepdims=True))
        r = (p / p.sum(1, keepdims=True) - targets) / n
        w_before, b_before = w, b
        w, b = wa - step * (r.T @ x + penalty * wa), ba - step * r.sum(0)
    return w, b


def run(frames, labels, folds, k, family):
    """Validation and test accuracy of one run (validation fold k, test fold TEST_FOLD), and the
    penalty its validation fold chose."""
    train, val, test = (folds != k) & (folds != TEST_FOLD), folds == k, folds == TEST_FOLD
    mean = frames[train].mean((0, 1))
    std = frames[train].std((0, 1)) + 1e-3
    h, w = frames.shape[2:4]
    ring = ring_of(h, w, RINGS)
    soft, with_histogram = family.startswith(("soft", "logs", "gradients")), family != "rings" and family != "rings-frames"
    rows, touches = [], []
    for touch in frames:
        v = ((touch - mean) / std).transpose(0, 3, 1, 2)  # [T, C, H, W]
        level, power, histogram = per_frame(v, ring, soft, family.startswith("gradients"))
        parts = [level, np.log(power + 1e-6).reshape(len(v), -1)]
        whole = [level.mean(0), np.log(power.mean(0) + 1e-6).ravel()]
        if with_histogram:
            parts.append(histogram.reshape(len(v), -1))
            whole.append(histogram.mean(0).ravel())
        rows.append(np.concatenate(parts, 1))
        # `logs-frames` reads a touch as its frames' rows read: their mean.
        touches.append(rows[-1].mean(0) if family == "logs-frames" else np.concatenate(whole))
    rows, touches = np.array(rows), np.array(touches)
    if family.endswith("frames"):
        x, y = rows[train].reshape(-1, rows.shape[2]), np.repeat(labels[train], rows.shape[1])
    else:
        x, y = touches[train], labels[train]
    mu, sd = x.mean(0), x.std(0) + 1e-6
    z = lambda a: (a - mu) / sd  # noqa: E731
    classes = labels.max() + 1

    def accuracy(fit, which):
        scores = z(touches[which]) @ fit[0].T + fit[1]
        return (scores.argmax(1) == labels[which]).mean()

    fits = [logistic(z(x), y, classes, p) for p in PENALTIES]
    scores = [accuracy(f, val) for f in fits]
    best = int(np.argmax(scores))  # the strongest penalty among equals
    return scores[best], accuracy(fits[best], test), PENALTIES[best]


def arguments():
    """The command line, `--help` the module's docs."""
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("data", help="an imported camera data set (.npz)")
    p.add_argument("runs", help="a `pvt3 cv` directory, whose runs' splits are read")
    p.add_argument("families", nargs="*", metavar="FAMILY", help=f"the families to fit, of {', '.join(FAMILIES)} (all of them if none)")
    p.add_argument("--rings", type=int, default=LAYOUT[0], help="rings of spatial frequency (the camera layout's spectral_bands)")
    p.add_argument("--bins", type=int, default=LAYOUT[1], help="histogram bins (the camera layout's spectral_histogram)")
    p.add_argument("--only", help="SEED:FOLD,...: these runs (seed, validation fold) alone")
    a = p.parse_args()
    unknown = [f for f in a.families if f not in FAMILIES]
    if unknown:
        p.error(f"unknown families {unknown}; the families are {FAMILIES}")
    a.families = a.families or FAMILIES
    return a


def main():
    global RINGS, BINS
    a = arguments()
    RINGS, BINS = a.rings, a.bins
    only = a.only and {tuple(int(v) for v in pair.split(":")) for pair in a.only.split(",")}
    data = np.load(a.data)
    x, labels = data["x"], data["y"].astype(int)
    if x.ndim == 4:
        x = x[:, :, :, None, :]
    frames = x.transpose(0, 4, 1, 2, 3).astype(np.float32)  # [N, T, H, W, C]
    recorded = [r for r in runs(a.runs) if not only or r[:2] in only]
    for family in a.families:
        label = family if (RINGS, BINS) == LAYOUT else f"{family} (rings {RINGS}, bins {BINS})"
        results, vals = [], []
        for seed, k, folds in recorded:
            val, test, penalty = run(frames, labels, folds, k, family)
            results.append((seed, test))
            vals.append(val)
            print(f"{label}: seed {seed} fold {k}: validation {val:.4f}, test {test:.4f}, penalty {penalty:g}", file=sys.stderr)
        tests = [t for _, t in results]
        line = f"{label}: {len(tests)} runs, validation {statistics.mean(vals):.4f}, test {statistics.mean(tests):.4f}"
        seeds = sorted({s for s, _ in results})
        if len(tests) > 1:
            line += f" ± {statistics.stdev(tests):.4f}"
        if len(seeds) > 1:
            means = [statistics.mean(t for s, t in results if s == seed) for seed in seeds]
            half = t_975(len(means) - 1) * statistics.stdev(means) / len(means) ** 0.5
            m = statistics.mean(means)
            line += f"; seed means {', '.join(f'{v:.4f}' for v in means)}, 95 % interval [{m - half:.4f}, {m + half:.4f}]"
        print(line, flush=True)


if __name__ == "__main__":
    main()
