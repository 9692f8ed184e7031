"""Statistics of the selection-mask scores of trained runs: for every mask, the count, mean, minimum,
quartile, median and maximum of |score| (docs/pruning.md). Needs numpy and safetensors
(e.g. target/bench-venv from bench/train_speed.sh).

    python bench/mask_scores.py RUN [RUN …]
"""
import sys

import numpy as np
from safetensors.numpy import load_file

for run in sys.argv[1:]:
    tensors = load_file(run + "/model/weights.safetensors")
    print(run)
    for name in sorted(k for k in tensors if "mask" in k):
        v = np.abs(tensors[name].ravel())
        print(f"  {name:40s} n={v.size:3d} mean={v.mean():.3f} min={v.min():.3f} p25={np.percentile(v, 25):.3f} "
              f"p50={np.median(v):.3f} max={v.max():.3f}")
