"""What the network is given to see: a logistic regression on the spectral head's features alone.

    python3 -m venv target/probe-venv && target/probe-venv/bin/pip install numpy scikit-learn
    target/probe-venv/bin/python bench/spectral_probe.py

The features are those of PVT³'s spectral head (models/src/spectrum.rs, `--set spectral_bands=16`):
per channel (taxel or electrode) of the normalised window, its mean level and the log power of 16
geometrically spaced frequency bands of the detrended signal. Under the published protocol (for
each validation fold k in 0-3, train on the folds other than k and 4, test on fold 4; the
validation fold has nothing to select here), scikit-learn's multinomial logistic regression (L2
penalty, C = 0.1) on the features standardised over the training folds.
It is deterministic: the four runs differ only in their training folds. Prints, per data set, the
mean ± std of the four test accuracies, for the whole window and for its first 10 % of frames.
"""
import numpy as np
from sklearn.linear_model import LogisticRegression

BANDS = 16
C = 0.1


def band_edges(frames, bands):
    """models/src/spectrum.rs `band_edges`: geometric from frequency 1 to frames / 2, each band at
    least one frequency wide."""
    top = frames // 2 + 1
    edges = [1]
    for j in range(1, bands + 1):
        geometric = int(np.floor(top ** (j / bands) + 0.5))
        edges.append(min(max(geometric, edges[-1] + 1), top - (bands - j)))
    return edges


def features(x, bands):
    """`[n, channels, frames]` normalised windows → `[n, channels · (1 + bands)]`, as the head's."""
    frames = x.shape[2]
    level = x.mean(2, keepdims=True)
    power = np.abs(np.fft.rfft(x - level, axis=2)) ** 2 / frames
    edges = band_edges(frames, bands)
    log_power = np.stack([np.log(power[:, :, a:b].sum(2) + 1e-6) for a, b in zip(edges[:-1], edges[1:])], 2)
    return np.concatenate([level, log_power], 2).reshape(len(x), -1)


def probe(name, share):
    data = np.load(f"data/{name}.npz")
    x, y, fold = data["x"].astype(np.float64), data["y"], data["fold"]
    x = x.reshape(len(x), -1, x.shape[-1])
    x = x[:, :, : int(round(share * x.shape[2]))]
    accuracies = []
    for k in range(4):
        train, test = (fold != k) & (fold != 4), fold == 4
        # Per-channel normalisation fitted on the training folds, as the trainer's.
        mean, std = x[train].mean((0, 2), keepdims=True), x[train].std((0, 2), keepdims=True) + 1e-9
        f = features((x - mean) / std, BANDS)
        mu, sd = f[train].mean(0), f[train].std(0) + 1e-6
        g = (f - mu) / sd
        model = LogisticRegression(C=C, max_iter=5000).fit(g[train], y[train])
        accuracies.append(model.score(g[test], y[test]))
    print(f"{name}, first {share:.0%} of the frames: {np.mean(accuracies):.4f} ± {np.std(accuracies, ddof=1):.4f} "
          f"(folds: {', '.join(f'{a:.3f}' for a in accuracies)})")


for name in ["biotac20", "icub20"]:
    for share in [1.0, 0.1]:
        probe(name, share)
