"""Classify windows with a pvt3 .onnx in onnxruntime, without pvt3 (docs/deploy.md, "The file in
onnxruntime"). The tests run it on the golden model and compare with the runtime.

    python runtime/examples/onnxruntime_classify.py MODEL.onnx WINDOWS.npy

WINDOWS.npy: raw sensor values, one window [height, width, (channels,) frames] or a batch of them.
Prints one line per window: index, class index, class name, its probability.
"""

import json
import sys

import numpy as np
import onnxruntime as ort

session = ort.InferenceSession(sys.argv[1], providers=["CPUExecutionProvider"])
meta = session.get_modelmeta().custom_metadata_map
classes = json.loads(meta["pvt3.classes"])  # the class names, in the order of the outputs
(frames,) = session.get_inputs()  # "frames": float32 [batch, height, width, (channels,) frames]
windows = np.load(sys.argv[2]).astype(np.float32)  # raw values: the normalisation is in the graph
if windows.ndim == len(frames.shape) - 1:
    windows = windows[None]  # one window: a batch of one
(probabilities,) = session.run(["probabilities"], {frames.name: windows})  # [batch, classes]
for i, p in enumerate(probabilities):
    k = int(p.argmax())
    print(f"{i}\t{k}\t{classes[k]}\t{p[k]:.6f}")
