"""onnxruntime's own per-operator profile of a pvt3 .onnx, the peer of the runtime's
`profile` tool (bench/tools/src/bin/profile.rs): one intra-op thread, synthetic input as
`ort_latency.py` gives, `SessionOptions.enable_profiling`. Prints a Markdown table of time per
operator kind (summed over nodes, per run), largest first, and with --nodes N the N slowest nodes.

    python bench/ort_profile.py MODEL.onnx [--batch B] [--runs R] [--nodes N]
"""
import argparse
import collections
import json
import os
import tempfile

import numpy as np
import onnxruntime as ort


def profile(path, batch, runs):
    """The profile's node events (name, operator, microseconds) over `runs` runs after 5."""
    options = ort.SessionOptions()
    options.intra_op_num_threads = 1
    options.inter_op_num_threads = 1
    options.enable_profiling = True
    options.profile_file_prefix = os.path.join(tempfile.mkdtemp(), "ort")
    session = ort.InferenceSession(path, options, providers=["CPUExecutionProvider"])
    shape = [d for d in session.get_inputs()[0].shape[1:]]
    frames = np.random.default_rng(0).standard_normal([batch, *shape]).astype(np.float32)
    for _ in range(5 + runs):
        session.run(None, {"frames": frames})
    kernels = [e for e in json.load(open(session.end_profiling()))
               if e.get("cat") == "Node" and e["name"].endswith("_kernel_time")]
    # Every run records the same nodes; the first five runs warm up.
    per_run = len(kernels) // (5 + runs)
    return [(e["name"].removesuffix("_kernel_time"), e["args"]["op_name"], e["dur"]) for e in kernels[5 * per_run:]]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("model")
    parser.add_argument("--batch", type=int, default=1)
    parser.add_argument("--runs", type=int, default=200)
    parser.add_argument("--nodes", type=int, default=0)
    args = parser.parse_args()
    events = profile(args.model, args.batch, args.runs)
    by_op, by_node, calls = collections.Counter(), collections.Counter(), collections.Counter()
    for name, op, us in events:
        by_op[op] += us
        by_node[(name, op)] += us
        calls[op] += 1
    total = sum(by_op.values())
    print(f"onnxruntime {ort.__version__}, batch {args.batch}, {args.runs} runs, one thread\n")
    print("| operator | nodes | µs per run | share |\n|---|---:|---:|---:|")
    for op, us in by_op.most_common():
        print(f"| {op} | {calls[op] // args.runs} | {us / args.runs:.1f} | {100 * us / total:.1f} % |")
    print(f"| **all nodes** | {len(by_node)} | {total / args.runs:.1f} | |")
    if args.nodes:
        print("\n| node | operator | µs per run |\n|---|---|---:|")
        for (name, op), us in by_node.most_common(args.nodes):
            print(f"| {name} | {op} | {us / args.runs:.1f} |")


if __name__ == "__main__":
    main()
