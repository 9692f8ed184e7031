"""The leading table of docs/benchmarks.md: every shipped file on every product path this CPU
can run, beside onnxruntime, and against the core's peak.

Each round runs, per file, `pvt3-run --bench` once per path (the runtime's own products in each
instruction set the CPU has, forced with PVT3_SMALL_PRODUCTS, and `none`: tract's kernels for
every product) and `bench/ort_latency.py` once (one thread each), in turn, so that the machine's
noise falls on all of them; the table gives medians over the rounds. On a CPU with AVX-512 the
`avx2` row is the runtime's AVX2 path, not an AVX2-only CPU: tract's own kernels there still use
AVX-512.

The work a window asks is counted from the file: the multiply-adds of its matrix products and of
its products summed over an axis (the attention's scores and mixing), at batch 1, from ONNX's
shape inference. The peak is lanes × FMA units × 2 × the clock (`/proc/cpuinfo`'s MHz, or
--ghz), with --fma-units per core (2 on every x86 core of the last decade with AVX2 or AVX-512).

    target/onnx-venv/bin/python bench/isa_paths.py [--rounds 5] [--seconds 1] [FILE.onnx ...]
"""
import argparse
import json
import os
import statistics
import subprocess
import sys

import numpy as np
import onnx
from onnx import shape_inference

LANES = {"avx512": 16, "avx2": 8}


def multiply_adds(path):
    """Multiply-adds per window of `path`'s matrix products and summed products, at batch 1."""
    model = onnx.load(path)
    model.graph.input[0].type.tensor_type.shape.dim[0].dim_value = 1
    model = shape_inference.infer_shapes(model, data_prop=True)
    values = list(model.graph.value_info) + list(model.graph.input) + list(model.graph.output)
    shapes = {v.name: [d.dim_value for d in v.type.tensor_type.shape.dim] for v in values}
    shapes.update({i.name: list(i.dims) for i in model.graph.initializer})
    producer = {o: n for n in model.graph.node for o in n.output}
    total = 0
    for n in model.graph.node:
        if n.op_type in ("MatMul", "Gemm"):
            total += int(np.prod(shapes[n.output[0]])) * shapes[n.input[0]][-1]
        elif n.op_type == "ReduceSum" and getattr(producer.get(n.input[0]), "op_type", None) == "Mul":
            total += int(np.prod(shapes[n.input[0]]))
    return total


def cpu():
    """This CPU's instruction sets (widest first) and clock in GHz, from /proc/cpuinfo."""
    text = open("/proc/cpuinfo").read()
    flags = set(next(l for l in text.splitlines() if l.startswith("flags")).split(":")[1].split())
    mhz = float(next(l for l in text.splitlines() if l.startswith("cpu MHz")).split(":")[1])
    sets = [s for s, needs in (("avx512", {"avx512f"}), ("avx2", {"avx2", "fma"})) if needs <= flags]
    return sets, mhz / 1e3


def run(cmd, env=None):
    out = subprocess.run(cmd, capture_output=True, text=True, check=True, env=env).stdout
    return json.loads(out)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--seconds", type=float, default=1.0)
    p.add_argument("--runner", default="target/robot/pvt3-run")
    p.add_argument("--ghz", type=float, help="the core's clock (default: /proc/cpuinfo)")
    p.add_argument("--fma-units", type=int, default=2)
    p.add_argument("files", nargs="*", default=["shipped/icub20.onnx", "shipped/biotac20.onnx", "shipped/physiclear.onnx"])
    a = p.parse_args()
    sets, ghz = cpu()
    ghz = a.ghz or ghz
    paths = sets + ["none"]
    pvt3 = {(f, path): [] for f in a.files for path in paths}
    ort = {f: [] for f in a.files}
    for r in range(a.rounds):
        for f in a.files:
            print(f"round {r + 1}/{a.rounds}: {f}", file=sys.stderr)
            for path in paths:
                env = dict(os.environ, PVT3_SMALL_PRODUCTS=path)
                env.pop("RUST_BACKTRACE", None)
                pvt3[f, path].append(run([a.runner, "--bench", f, "1", str(a.seconds)], env))
            ort[f].append(run([sys.executable, "bench/ort_latency.py", f, str(a.seconds)]))
    med = lambda xs, k: statistics.median(x[k] for x in xs)
    print(f"{a.rounds} rounds, one thread, {ghz:.2f} GHz, {a.fma_units} FMA units a core; "
          f"paths {', '.join(paths)}; {a.runner}\n")
    print("| file | multiply-adds a window | path | batch | pvt3 | onnxruntime | pvt3 / onnxruntime | pvt3 GFLOP/s | share of the core's peak |")
    print("|---|---:|---|---:|---:|---:|---:|---:|---:|")
    for f in a.files:
        macs = multiply_adds(f)
        name = os.path.basename(f)
        for path in paths:
            # tract's kernels (`none`) use the widest set the CPU has.
            peak = LANES.get(path, LANES[sets[0]] if sets else 4) * a.fma_units * 2 * ghz
            ps, os_ = pvt3[f, path], ort[f]
            b1, o1 = med(ps, "batch1_median_us"), med(os_, "batch1_median_us")
            w32, o32 = med(ps, "batch32_windows_per_second"), med(os_, "batch32_windows_per_second")
            ratios1 = [p["batch1_median_us"] / o["batch1_median_us"] for p, o in zip(ps, os_)]
            ratios32 = [p["batch32_windows_per_second"] / o["batch32_windows_per_second"] for p, o in zip(ps, os_)]
            g1, g32 = 2 * macs / b1 / 1e3, 2 * macs * w32 / 1e9
            print(f"| {name} | {macs / 1e6:.2f} M | {path} | 1 | {b1:,.0f} µs (p99 {med(ps, 'batch1_p99_us'):,.0f}) | {o1:,.0f} µs | "
                  f"{statistics.median(ratios1):.2f} time ({min(ratios1):.2f}–{max(ratios1):.2f}) | {g1:.1f} | {100 * g1 / peak:.0f} % |")
            print(f"| {name} | | {path} | 32 | {w32:,.0f} windows/s ({ps[0]['windows_per_run']} a run) | {o32:,.0f} windows/s | "
                  f"{statistics.median(ratios32):.2f} throughput ({min(ratios32):.2f}–{max(ratios32):.2f}) | {g32:.1f} | {100 * g32 / peak:.0f} % |")
    print("\n| file | path | pvt3 batch 1, the fixed rule (µs) | pvt3 batch 1, tract's kernels (µs) | first answer after load: pvt3 (ms) | onnxruntime session and first run (ms) |")
    print("|---|---|---:|---:|---:|---:|")
    for f in a.files:
        for path in paths:
            ps = pvt3[f, path]
            first = statistics.median(p["load_ms"] + p["batch1_first_call_ms"] for p in ps)
            print(f"| {os.path.basename(f)} | {path} | {med(ps, 'batch1_median_us'):,.0f} | {med(ps, 'batch1_untuned_median_us'):,.0f} | "
                  f"{first:.1f} | {med(ort[f], 'first_call_ms'):.1f} |")


if __name__ == "__main__":
    main()
