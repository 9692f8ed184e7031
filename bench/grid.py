"""The run-time-versus-error frontier of docs/benchmarks.md. For each model of a grid (one
`NAME=GLOB` per argument: the run directories of that model, one per fold), it takes the mean
test accuracy over the folds, the baked parameters and multiply-adds (`pvt3 info`), and, for the
first fold's model exported to ONNX, the latency in the pvt3 runtime (`pvt3-run --bench`, robot
profile unless `--runner` names another build; also with tract's own kernel choice, untuned) and in
onnxruntime (`bench/ort_latency.py`), measured side by side in rounds. Prints a markdown table and
writes the plot as SVG.

    target/onnx-venv/bin/python bench/grid.py --svg docs/frontier.svg \\
        unpruned='runs/cv-icub20-l1/seed0/fold?' channels50='runs/cv-icub20-l1/seed0/fold?/pruned' …
"""
import argparse
import glob
import json
import re
import statistics
import subprocess
import sys
from pathlib import Path

PVT3 = "./target/release/pvt3"


def info(run):
    out = subprocess.run([PVT3, "info", run], capture_output=True, text=True, check=True).stdout
    m = re.search(r"after baking\s+(\d+) parameters, (\d+) multiply-adds per sample, (\d+) of (\d+)", out)
    return int(m[1]), int(m[2]), f"{m[3]}/{m[4]}"


def bench(cmd):
    return json.loads(subprocess.run(cmd, capture_output=True, text=True, check=True).stdout)


def svg(rows, path):
    """Test error against batch-1 latency, both engines, each model labelled."""
    w, h, pad = 640, 420, 60
    xs = [r[k] for r in rows for k in ("pvt3_us", "ort_us")]
    ys = [1 - r["accuracy"] for r in rows]
    x0, x1 = 0, max(xs) * 1.1
    y0, y1 = 0, max(ys) * 1.2
    X = lambda v: pad + (v - x0) / (x1 - x0) * (w - 2 * pad)
    Y = lambda v: h - pad - (v - y0) / (y1 - y0) * (h - 2 * pad)
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="11">',
           f'<rect width="{w}" height="{h}" fill="white"/>',
           f'<line x1="{pad}" y1="{h - pad}" x2="{w - pad}" y2="{h - pad}" stroke="black"/>',
           f'<line x1="{pad}" y1="{pad}" x2="{pad}" y2="{h - pad}" stroke="black"/>',
           f'<text x="{w / 2}" y="{h - 20}" text-anchor="middle">batch-1 latency, one thread (µs)</text>',
           f'<text x="18" y="{h / 2}" transform="rotate(-90 18 {h / 2})" text-anchor="middle">test error (mean over folds)</text>',
           f'<circle cx="{w - 190}" cy="20" r="4" fill="#1f77b4"/><text x="{w - 180}" y="24">pvt3 runtime (tract)</text>',
           f'<rect x="{w - 194}" y="32" width="8" height="8" fill="#ff7f0e"/><text x="{w - 180}" y="40">onnxruntime, same file</text>']
    for t in range(5):
        xv, yv = x0 + t * (x1 - x0) / 4, y0 + t * (y1 - y0) / 4
        out.append(f'<text x="{X(xv)}" y="{h - pad + 15}" text-anchor="middle">{xv:.0f}</text>')
        out.append(f'<text x="{pad - 5}" y="{Y(yv) + 4}" text-anchor="end">{yv:.3f}</text>')
    for r in rows:
        y = Y(1 - r["accuracy"])
        out.append(f'<line x1="{X(r["ort_us"])}" y1="{y}" x2="{X(r["pvt3_us"])}" y2="{y}" stroke="#bbb"/>')
        out.append(f'<circle cx="{X(r["pvt3_us"])}" cy="{y}" r="4" fill="#1f77b4"/>')
        out.append(f'<rect x="{X(r["ort_us"]) - 4}" y="{y - 4}" width="8" height="8" fill="#ff7f0e"/>')
        out.append(f'<text x="{X(r["pvt3_us"]) + 7}" y="{y + 4}">{r["name"]}</text>')
    out.append("</svg>")
    Path(path).write_text("\n".join(out) + "\n")


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--svg", required=True)
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--seconds", type=float, default=1.0)
    p.add_argument("--runner", default="./target/robot/pvt3-run", help="the pvt3-run binary to time")
    p.add_argument("models", nargs="+", help="NAME=GLOB of run directories, one per fold")
    a = p.parse_args()
    Path("target/grid").mkdir(parents=True, exist_ok=True)
    rows = []
    for spec in a.models:
        name, pattern = spec.split("=", 1)
        runs = sorted(r for r in glob.glob(pattern) if Path(r, "result.json").exists())
        acc = [json.loads(Path(r, "result.json").read_text())["test_accuracy"] for r in runs]
        onnx = f"target/grid/{name}.onnx"
        subprocess.run([PVT3, "export", runs[0], "-o", onnx], capture_output=True, check=True)
        params, macs, kept = info(runs[0])
        rows.append(dict(name=name, runs=len(runs), accuracy=statistics.mean(acc), params=params, macs=macs, kept=kept, onnx=onnx,
                         pvt3=[], ort=[]))
    for i in range(a.rounds):
        for r in rows:
            print(f"round {i + 1}/{a.rounds}: {r['name']}", file=sys.stderr)
            r["pvt3"].append(bench([a.runner, "--bench", r["onnx"], "1", str(a.seconds)]))
            r["ort"].append(bench([sys.executable, "bench/ort_latency.py", r["onnx"], str(a.seconds)]))
    med = lambda xs, k: statistics.median(x[k] for x in xs)
    print("| model | folds | test accuracy | parameters | multiply-adds | tokens kept | pvt3 batch 1 median / p99 (µs) | pvt3 batch 1, untuned kernels (µs) | pvt3 batch 32 (windows/s) | onnxruntime batch 1 median (µs) | onnxruntime batch 32 (windows/s) | pvt3 / onnxruntime | speed-up over unpruned (pvt3, batch 1) |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    base = med(rows[0]["pvt3"], "batch1_median_us")
    for r in rows:
        r["pvt3_us"], r["ort_us"] = med(r["pvt3"], "batch1_median_us"), med(r["ort"], "batch1_median_us")
        print(f"| {r['name']} | {r['runs']} | {r['accuracy']:.4f} | {r['params']:,} | {r['macs'] / 1e6:.2f} M | {r['kept']} | "
              f"{r['pvt3_us']:.0f} / {med(r['pvt3'], 'batch1_p99_us'):.0f} | {med(r['pvt3'], 'batch1_untuned_median_us'):.0f} | "
              f"{med(r['pvt3'], 'batch32_windows_per_second'):.0f} | "
              f"{r['ort_us']:.0f} | {med(r['ort'], 'batch32_windows_per_second'):.0f} | {r['pvt3_us'] / r['ort_us']:.2f} | {base / r['pvt3_us']:.2f}× |")
    svg(rows, a.svg)


if __name__ == "__main__":
    main()
