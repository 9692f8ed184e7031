"""onnxruntime latency of a pvt3 .onnx, measured like `pvt3-run --bench`: batch 1 (median, p99)
and batch 32 (windows per second), one intra-op thread, synthetic input; and the first answer
(the session's creation and its first run, the peer of the runtime's load and first call).
Prints one JSON line.

    python bench/ort_latency.py MODEL.onnx [SECONDS]
"""
import json
import sys
import time

import numpy as np
import onnxruntime as ort


def sample(budget, minimum, f):
    for _ in range(3):
        f()
    times, start = [], time.perf_counter()
    while len(times) < minimum or time.perf_counter() - start < budget:
        t = time.perf_counter()
        f()
        times.append(time.perf_counter() - t)
    return np.array(times)


def main():
    path, seconds = sys.argv[1], float(sys.argv[2]) if len(sys.argv) > 2 else 2.0
    options = ort.SessionOptions()
    options.intra_op_num_threads = 1
    options.inter_op_num_threads = 1
    started = time.perf_counter()
    session = ort.InferenceSession(path, options, providers=["CPUExecutionProvider"])
    shape = [d for d in session.get_inputs()[0].shape[1:]]
    rng = np.random.default_rng(0)
    one = rng.standard_normal([1, *shape]).astype(np.float32)
    session.run(None, {"frames": one})
    first_call_ms = (time.perf_counter() - started) * 1e3
    many = rng.standard_normal([32, *shape]).astype(np.float32)
    b1 = sample(seconds, 20, lambda: session.run(None, {"frames": one}))
    b32 = sample(seconds, 5, lambda: session.run(None, {"frames": many}))
    print(json.dumps({
        "model": path,
        "onnxruntime": ort.__version__,
        "batch1_median_us": float(np.median(b1) * 1e6),
        "batch1_p99_us": float(np.percentile(b1, 99) * 1e6),
        "batch32_windows_per_second": float(32 * len(b32) / b32.sum()),
        "first_call_ms": first_call_ms,
    }))


if __name__ == "__main__":
    main()
