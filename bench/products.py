"""The iCub model's matrix products one at a time, in both engines: the pvt3 runtime (tract, timed
by `bench/tools/src/bin/profile.rs`, built with `cargo build --release -p pvt3-bench-tools --bin
profile`), with its products tuned as the runtime tunes them and with tract's own kernels, and
onnxruntime (one intra-op thread). Each file is one product with a bias,
`[m, k] x [k, n]`; an Identity file shows what a call that does nothing costs each engine.
Prints a markdown table (docs/benchmarks.md).

With `--k-sweep [M N]` (default 375 × 40), it instead times one product shape over growing k in the runtime alone: the
default fixed kernel rule, tract's own kernels, and kernels measured at load (and which one that
measurement kept), to check the fixed rule against measurement (docs/benchmarks.md, step 18).

    target/onnx-venv/bin/python bench/products.py [RUNS] [--k-sweep [M N]]
"""
import os
import re
import subprocess
import sys
import tempfile
import time

import numpy as np
import onnx
import onnxruntime as ort
from onnx import TensorProto, helper, numpy_helper

PROFILE = "target/release/profile"
SHAPES = [
    ("a call that does nothing (Identity)", 375, 20, None),
    ("spatial queries, output projection (unpruned)", 375, 20, 20),
    ("spatial fc1 (unpruned)", 375, 20, 40),
    ("spatial fc2 (unpruned)", 375, 40, 20),
    ("temporal scores", 76, 20, 76),
    ("temporal fc1", 76, 20, 40),
]


def write(path, m, k, n):
    x = helper.make_tensor_value_info("x", TensorProto.FLOAT, [m, k])
    y = helper.make_tensor_value_info("y", TensorProto.FLOAT, None)
    if n is None:
        nodes, inits = [helper.make_node("Identity", ["x"], ["y"])], []
    else:
        rng = np.random.default_rng(0)
        w = numpy_helper.from_array(rng.standard_normal((k, n)).astype(np.float32), "w")
        b = numpy_helper.from_array(rng.standard_normal(n).astype(np.float32), "b")
        nodes, inits = [helper.make_node("MatMul", ["x", "w"], ["p"]), helper.make_node("Add", ["p", "b"], ["y"])], [w, b]
    model = helper.make_model(helper.make_graph(nodes, "product", [x], [y], inits), opset_imports=[helper.make_opsetid("", 17)])
    model.ir_version = 8
    onnx.save(model, path)


def tract_us(path, shape, runs, kernels="fixed"):
    """tract's median time for one-input `path` at `shape` with the runtime's plan, its products'
    kernels chosen as `kernels` says (fixed, tract or measured), untimed nodes; and the operator
    that ran the slowest node (the product)."""
    env = dict(os.environ, PVT3_PROFILE_SHAPE=",".join(map(str, shape)), PVT3_PROFILE_KERNELS=kernels, PVT3_PROFILE_NODES="1")
    out = subprocess.run([PROFILE, path, "1", str(runs)], env=env, capture_output=True, text=True, check=True).stdout
    slowest = out.split("| node | operator |")[1].splitlines()[2].split("|")[2].strip()
    return float(re.search(r"untimed nodes \(median\) \| \| ([\d.]+)", out)[1]), slowest


def ort_us(path, shape, runs):
    """onnxruntime's median time for one-input `path` at `shape`, one intra-op thread."""
    options = ort.SessionOptions()
    options.intra_op_num_threads = 1
    options.inter_op_num_threads = 1
    session = ort.InferenceSession(path, options, providers=["CPUExecutionProvider"])
    feed = {session.get_inputs()[0].name: np.random.default_rng(1).standard_normal(shape).astype(np.float32)}
    for _ in range(50):
        session.run(None, feed)
    times = []
    for _ in range(runs):
        t = time.perf_counter()
        session.run(None, feed)
        times.append(time.perf_counter() - t)
    return float(np.median(times) * 1e6)


def k_sweep(runs, m, n):
    print(f"tract as linked by pvt3-runtime; `{m} × k × {n}` plus a bias, {runs} runs each, one thread.\n")
    print("| k | fixed rule (µs) | tract's own kernels (µs) | measured at load (µs) | kernel the measurement kept |")
    print("|---:|---:|---:|---:|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for k in [20, 40, 64, 128, 256, 512, 1024, 4800]:
            path = os.path.join(tmp, "product.onnx")
            write(path, m, k, n)
            (f, _), (t, _), (w, kept) = (tract_us(path, [m, k], runs, kernels) for kernels in ("fixed", "tract", "measured"))
            print(f"| {k} | {f:.1f} | {t:.1f} | {w:.1f} | {kept} |")


def main():
    numbers = [int(a) for a in sys.argv[1:] if not a.startswith("-")]
    runs = numbers[0] if numbers else 3000
    if "--k-sweep" in sys.argv:
        m, n = numbers[1:3] if len(numbers) >= 3 else (375, 40)
        return k_sweep(runs, m, n)
    print(f"onnxruntime {ort.__version__}; tract as linked by pvt3-runtime; {runs} runs each, one thread.\n")
    print("| product | m × k × n | pvt3 runtime (µs per call, median) | tract's own kernels (µs) | onnxruntime (µs) | pvt3 / onnxruntime, less the empty call |")
    print("|---|---|---:|---:|---:|---:|")
    empty = None
    with tempfile.TemporaryDirectory() as tmp:
        for name, m, k, n in SHAPES:
            path = os.path.join(tmp, "product.onnx")
            write(path, m, k, n)
            (t, _), (u, _), o = tract_us(path, [m, k], runs), tract_us(path, [m, k], runs, "tract"), ort_us(path, [m, k], runs)
            if n is None:
                empty = (t, o)
                print(f"| {name} | {m} × {k} | {t:.1f} | {u:.1f} | {o:.1f} | |")
            else:
                print(f"| {name} | {m} × {k} × {n} | {t:.1f} | {u:.1f} | {o:.1f} | {(t - empty[0]) / (o - empty[1]):.2f} |")


if __name__ == "__main__":
    main()
