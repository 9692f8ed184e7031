"""Exported models timed whole and stage by stage, in both engines: the spatial stage (raw frames
to token encodings) and the temporal stage (token encodings to logits), each cut out of the file
at its seam with `onnx.utils.extract_model`. tract is timed by `bench/tools/src/bin/profile.rs` (a cut
file has no pvt3 metadata, so it is read by tract's ONNX loader, where the runtime wires the same
operators itself; kernels chosen as the runtime chooses them, median of untimed runs), onnxruntime with one
intra-op thread (median), alternating in rounds (the median of the rounds is printed). Prints a
markdown table (docs/benchmarks.md).

    cargo build --release -p pvt3-bench-tools --bin profile
    target/onnx-venv/bin/python bench/stages.py [--runs N] [--rounds R] MODEL.onnx ...
"""
import argparse
import json
import os
import tempfile

import numpy as np
import onnx
import onnx.utils
import onnxruntime as ort

from products import ort_us, tract_us


def cut(src, dst, inputs, outputs):
    """The part of `src` between `inputs` and `outputs`, with shapes left for the engines to infer."""
    onnx.utils.extract_model(src, dst, inputs, outputs)
    m = onnx.load(dst)
    del m.graph.value_info[:]
    for o in m.graph.output:
        o.type.tensor_type.ClearField("shape")
    onnx.save(m, dst)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--runs", type=int, default=2000)
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("models", nargs="+")
    a = p.parse_args()
    print(f"onnxruntime {ort.__version__}; tract as built by pvt3-runtime (release); one thread; median of {a.runs} runs, "
          f"median of {a.rounds} rounds.\n")
    print("| model | part | tract (µs) | onnxruntime (µs) | tract / onnxruntime |")
    print("|---|---|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        for path in a.models:
            meta = {p.key: p.value for p in onnx.load(path).metadata_props}
            config = json.loads(meta["pvt3.config"])
            frames = [config["height"], config["width"]] + ([config["channels"]] if config["channels"] > 1 else []) + [config["frames"]]
            tokens = len(json.loads(meta["pvt3.kept_frames"])) // config["tubelet"]
            spatial, temporal = os.path.join(tmp, "spatial.onnx"), os.path.join(tmp, "temporal.onnx")
            cut(path, spatial, ["frames"], ["token_encodings"])
            cut(path, temporal, ["token_encodings"], ["logits"])
            parts = [("whole", path, [1] + frames), ("spatial stage", spatial, [1] + frames), ("temporal stage", temporal, [tokens, config["dim"]])]
            for part, file, shape in parts:
                rounds = [(tract_us(file, shape, a.runs), ort_us(file, shape, a.runs)) for _ in range(a.rounds)]
                t, o = (float(np.median([r[i] for r in rounds])) for i in (0, 1))
                print(f"| `{os.path.basename(path)}` | {part} | {t:.0f} | {o:.0f} | {t / o:.2f} |")


if __name__ == "__main__":
    main()
