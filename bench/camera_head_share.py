#!/usr/bin/env python3
"""What the transformer adds beside a camera model's fitted spectral head (docs/camera.md,
"Every frame a row"): each run of a `pvt3 cv` cross-validation exported twice, as trained and
with the head's linear map set to zero, both run in onnxruntime on every touch of the data set.
A PVT³'s logits are the transformer's plus the head's, so the second file gives the
transformer's alone and the difference the head's alone. Prints, per run and on average, the
validation and test accuracy of the whole model, of the head alone and of the transformer alone.

    target/onnx-venv/bin/python bench/camera_head_share.py DATA.npz CV_DIR [PVT3]   # numpy, onnxruntime

PVT3 is the trainer's binary (default target/release/pvt3). The files go to a temporary folder.
"""
import json
import shutil
import statistics
import struct
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import onnxruntime as ort

sys.path.insert(0, str(Path(__file__).parent))
from camera_linear import TEST_FOLD, runs  # noqa: E402


def without_head(run: Path, out: Path):
    """A copy of `run`'s model whose head's linear map (`spectral.linear.*`) is zero."""
    shutil.copytree(run / "model", out / "model")
    path = out / "model" / "weights.safetensors"
    data = bytearray(path.read_bytes())
    n = struct.unpack("<Q", data[:8])[0]
    header = json.loads(data[8 : 8 + n])
    zeroed = [k for k in header if k.startswith("spectral.linear.")]
    if not zeroed:
        sys.exit(f"{run}: no spectral head to take away")
    for k in zeroed:
        start, end = header[k]["data_offsets"]
        data[8 + n + start : 8 + n + end] = bytes(end - start)
    path.write_bytes(data)


def logits(model: Path, x: np.ndarray) -> np.ndarray:
    session = ort.InferenceSession(str(model), providers=["CPUExecutionProvider"])
    return np.concatenate([session.run(["logits"], {"frames": x[i : i + 32]})[0] for i in range(0, len(x), 32)])


def main():
    args = sys.argv[1:]
    if len(args) < 2:
        sys.exit(__doc__)
    pvt3 = args[2] if len(args) > 2 else "target/release/pvt3"
    data = np.load(args[0])
    x, labels = data["x"].astype(np.float32), data["y"].astype(int)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for seed, k, folds in runs(args[1]):
            run = Path(args[1]) / f"seed{seed}" / f"fold{k}"
            bare = Path(tmp) / f"seed{seed}-fold{k}"
            without_head(run, bare)
            for source, onnx in [(run, bare / "whole.onnx"), (bare, bare / "bare.onnx")]:
                subprocess.run([pvt3, "export", str(source), "--out", str(onnx)], check=True, capture_output=True)
            whole, transformer = logits(bare / "whole.onnx", x), logits(bare / "bare.onnx", x)
            forms = {"whole model": whole, "head alone": whole - transformer, "transformer alone": transformer}
            val, test = folds == k, folds == TEST_FOLD
            row = {f: ((l[val].argmax(1) == labels[val]).mean(), (l[test].argmax(1) == labels[test]).mean()) for f, l in forms.items()}
            rows.append(row)
            print(f"seed {seed} fold {k}: " + "; ".join(f"{f} {v:.4f} / {t:.4f}" for f, (v, t) in row.items()), flush=True)
    print(f"| {len(rows)} runs, mean | validation | test |\n|---|---:|---:|")
    for form in rows[0]:
        v, t = (statistics.mean(r[form][i] for r in rows) for i in (0, 1))
        print(f"| {form} | {v:.4f} | {t:.4f} |")


if __name__ == "__main__":
    main()
