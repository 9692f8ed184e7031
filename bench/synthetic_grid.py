#!/usr/bin/env python3
"""Two SYNTHETIC 32 x 32 taxel-array sets, written as a user's CSV folder (a folder a class, a
CSV a touch: a header p0 ... p1023, then a row a frame, row-major on the grid), for choosing the
layout of a large taxel grid (docs/results.md, "A large taxel grid"). No public high-density
array set could be fetched (a tactile glove's or a pressure mat's frames); these stand in for
one and are said to be synthetic wherever their figures appear.

    target/onnx-venv/bin/python bench/synthetic_grid.py slide OUT_DIR   # needs numpy
    target/onnx-venv/bin/python bench/synthetic_grid.py press OUT_DIR

- slide: a textured surface slides under the mat. Six textures (gratings of three periods and
  two orientations, a dot lattice, bumps of one scale), each touch at its own speed (0.3 to 1
  taxels a frame, either way), phase, force (the amplitude, 0.5 to 2) and contact patch (an
  ellipse of 8 to 14 taxels' radius, where it lies). What tells a class is the spatial pattern;
  the temporal frequency mixes period with speed.
- press: an object is pressed and released. Six contact shapes (disk, ring, bar, cross, two dots,
  square), each touch at its own place, angle, size (0.8 to 1.2), force and timing.

Both add crosstalk between neighbouring taxels and noise (sd 0.05 of the mean force), clip at
zero as a pressure reading does, and hold 40 touches of 40 frames a class, from a fixed seed.
"""
import sys
from pathlib import Path

import numpy as np

SIDE, FRAMES, TOUCHES = 32, 40, 40
yy, xx = np.mgrid[0:SIDE, 0:SIDE].astype(float)


def rotated(angle, cx=SIDE / 2, cy=SIDE / 2):
    """The grid's coordinates about (cx, cy), turned by angle."""
    c, s = np.cos(angle), np.sin(angle)
    return (xx - cx) * c + (yy - cy) * s, -(xx - cx) * s + (yy - cy) * c


def texture(kind, u, v):
    """Texture `kind`'s height at surface coordinates (u, v)."""
    if kind < 3:  # gratings of period 3, 4.5 and 7 taxels, across the sliding direction
        return 0.5 + 0.5 * np.sin(2 * np.pi * u / (3, 4.5, 7)[kind])
    if kind == 3:  # the same period-4.5 grating turned by 45 degrees
        return 0.5 + 0.5 * np.sin(2 * np.pi * (u + v) / (4.5 * np.sqrt(2)))
    if kind == 4:  # a lattice of dots, 5 taxels apart
        return np.exp(-(((u % 5) - 2.5) ** 2 + ((v % 5) - 2.5) ** 2) / 1.5)
    return np.sin(u / 1.7) * np.sin(v / 2.3) * 0.5 + 0.5 * np.sin((u - v) / 1.1) ** 2  # bumps


def slide(kind, rng):
    speed = rng.uniform(0.3, 1.0) * rng.choice([-1, 1])
    phase, force = rng.uniform(0, 50), rng.uniform(0.5, 2.0)
    cx, cy, rx, ry = rng.uniform(12, 20), rng.uniform(12, 20), rng.uniform(8, 14), rng.uniform(8, 14)
    contact = np.clip(1 - ((xx - cx) / rx) ** 2 - ((yy - cy) / ry) ** 2, 0, None) ** 0.5
    u, v = rotated(rng.normal(0, 0.1))
    frames = [texture(kind, u + phase + speed * t, v) * contact for t in range(FRAMES)]
    return force * np.stack(frames)


def shape(kind, u, v):
    """Contact shape `kind`'s pressure at object coordinates (u, v) (unit size ~ 5 taxels)."""
    r = np.hypot(u, v)
    if kind == 0:
        return (r < 5).astype(float)
    if kind == 1:
        return ((r > 3.5) & (r < 6)).astype(float)
    if kind == 2:
        return ((abs(u) < 8) & (abs(v) < 1.5)).astype(float)
    if kind == 3:
        return (((abs(u) < 6) & (abs(v) < 1.5)) | ((abs(v) < 6) & (abs(u) < 1.5))).astype(float)
    if kind == 4:
        return ((np.hypot(u - 4, v) < 2.5) | (np.hypot(u + 4, v) < 2.5)).astype(float)
    return ((abs(u) < 4.5) & (abs(v) < 4.5)).astype(float)


def press(kind, rng):
    size, force = rng.uniform(0.8, 1.2), rng.uniform(0.5, 2.0)
    u, v = rotated(rng.uniform(0, np.pi), rng.uniform(10, 22), rng.uniform(10, 22))
    footprint = shape(kind, u / size, v / size)
    start, hold = rng.integers(2, 12), rng.integers(10, 22)
    t = np.arange(FRAMES)
    level = np.clip(np.minimum((t - start) / 4, (start + hold + 4 - t) / 4), 0, 1)
    return force * level[:, None, None] * footprint


def blurred(frames):
    """Crosstalk: each taxel reads a quarter of each of its four neighbours."""
    p = np.pad(frames, ((0, 0), (1, 1), (1, 1)), mode="edge")
    return frames + 0.25 * (p[:, :-2, 1:-1] + p[:, 2:, 1:-1] + p[:, 1:-1, :-2] + p[:, 1:-1, 2:])


def main(kind, out):
    make, names = {"slide": (slide, ["fine", "medium", "coarse", "diagonal", "dots", "bumps"]),
                   "press": (press, ["disk", "ring", "bar", "cross", "pair", "square"])}[kind]
    rng = np.random.default_rng(0)
    header = ",".join(f"p{i}" for i in range(SIDE * SIDE))
    for k, name in enumerate(names):
        (out / name).mkdir(parents=True, exist_ok=True)
        for i in range(TOUCHES):
            frames = blurred(make(k, rng))
            frames = np.clip(frames + rng.normal(0, 0.05 * frames.mean() + 1e-3, frames.shape), 0, None)
            np.savetxt(out / name / f"touch{i:02}.csv", frames.reshape(FRAMES, -1), fmt="%.4f", delimiter=",", header=header, comments="")
    print(f"wrote {len(names) * TOUCHES} synthetic touches of {len(names)} classes to {out}")


if __name__ == "__main__":
    if len(sys.argv) != 3 or sys.argv[1] not in ("slide", "press"):
        sys.exit(__doc__)
    main(sys.argv[1], Path(sys.argv[2]))
