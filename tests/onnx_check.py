"""Check an exported PVT³ file with onnx and onnxruntime.

    python tests/onnx_check.py MODEL.onnx INPUT.npy EXPECTED.npy [--output logits] [--atol 1e-5] [--prefix TOKENS]

Runs onnx.checker.check_model(full_check=True), then the model in onnxruntime (CPU) on INPUT, and
compares the named output with EXPECTED. With --prefix, the file's key bias (the constant behind
`token_bias`) hides every temporal token from TOKENS on (-inf), as a streaming runtime does for a
touch so far. Exit status 0: checker passed and every element is within
--atol; 1: otherwise. The message names the worst element either way.
"""

import argparse
import sys

import numpy as np
import onnx
import onnx.numpy_helper
import onnxruntime as ort


def hide_tokens_from(model, tokens):
    """Sets the key bias (the initializer the `token_bias` Identity reads, [1, 1, 1, 1 + time tokens],
    the CLS token first) to 0 up to temporal token `tokens` and -inf after it."""
    (source,) = [n.input[0] for n in model.graph.node if "token_bias" in n.output]
    (bias,) = [t for t in model.graph.initializer if t.name == source]
    values = onnx.numpy_helper.to_array(bias).copy()
    values[..., tokens + 1 :] = -np.inf
    bias.CopyFrom(onnx.numpy_helper.from_array(values, source))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("model")
    ap.add_argument("input")
    ap.add_argument("expected")
    ap.add_argument("--output", default="logits")
    ap.add_argument("--atol", type=float, default=1e-5)
    ap.add_argument("--prefix", type=int, help="temporal tokens received (the touch so far)")
    args = ap.parse_args()

    try:
        onnx.checker.check_model(args.model, full_check=True)
    except Exception as e:  # the checker raises several exception types
        print(f"FAIL {args.model}: onnx checker: {e}")
        return 1
    model = onnx.load(args.model)
    if args.prefix is not None:
        hide_tokens_from(model, args.prefix)
    session = ort.InferenceSession(model.SerializeToString(), providers=["CPUExecutionProvider"])
    x = np.load(args.input).astype(np.float32)
    expected = np.load(args.expected).astype(np.float64)
    (got,) = session.run([args.output], {session.get_inputs()[0].name: x})
    if got.shape != expected.shape:
        print(f"FAIL {args.model}: output {args.output} has shape {got.shape}, expected {expected.shape}")
        return 1
    err = np.abs(got.astype(np.float64) - expected)
    worst = np.unravel_index(np.argmax(err), err.shape)
    verdict = "ok" if err.max() <= args.atol else "FAIL"
    print(
        f"{verdict} {args.model}: onnxruntime {ort.__version__}, batch {x.shape[0]}, worst |{args.output} - expected| "
        f"= {err.max():.3e} at {tuple(int(i) for i in worst)} (got {got[worst]:.7g}, expected {expected[worst]:.7g}), "
        f"tolerance {args.atol:g}"
    )
    return 0 if verdict == "ok" else 1


if __name__ == "__main__":
    sys.exit(main())
