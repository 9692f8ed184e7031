"""The run-time-versus-error frontier of docs/benchmarks.md. For each model of a grid (one
`NAME=DIR[:pruned]` per argument: a `pvt3 cv` directory of several seeds × 4 folds, `:pruned` for
its pruned runs, as `bash bench/baselines.sh` writes them; a joint one's other sensor with
`:partner` or `:partner-pruned`), it takes the mean ± std of the test
accuracy over the runs from the directory's cv.json, the baked parameters and multiply-adds
(`pvt3 info`), and, for the first run's model exported to ONNX, the latency in the pvt3 runtime (`pvt3-run --bench`, robot
profile unless `--runner` names another build; also with tract's own kernel choice, untuned) and in
onnxruntime (`bench/ort_latency.py`), measured side by side in rounds. Prints a markdown table and
writes the plot as SVG, the error bars one standard deviation of the runs.

    target/onnx-venv/bin/python bench/grid.py --svg docs/frontier.svg \\
        unpruned=runs/cv-masks-icub channels50=runs/cv-masks-icub-channels50:pruned …
"""
import argparse
import math
import json
import re
import statistics
import subprocess
import sys
from pathlib import Path

from comparison import PVT3, cv_part


def info(run):
    out = subprocess.run([PVT3, "info", run], capture_output=True, text=True, check=True).stdout
    m = re.search(r"after baking\s+(\d+) parameters, (\d+) multiply-adds per sample, (\d+) of (\d+)", out)
    return int(m[1]), int(m[2]), f"{m[3]}/{m[4]}"


def bench(cmd):
    return json.loads(subprocess.run(cmd, capture_output=True, text=True, check=True).stdout)


def end_of_touch(measurements):
    """The median time from a streamed touch's last frame to its answer, or — for a file that
    is classified whole only."""
    times = [m["stream_end_of_touch_median_us"] for m in measurements if "stream_end_of_touch_median_us" in m]
    return f"{statistics.median(times):.0f}" if times else "—"


def ticks(lo, hi, most=6):
    """Round tick values (1, 2 or 5 times a power of ten apart) from lo to hi."""
    raw = (hi - lo) / most
    power = 10 ** math.floor(math.log10(raw))
    step = next(m * power for m in (1, 2, 5, 10) if m * power >= raw)
    first = math.ceil(lo / step) * step
    return [first + i * step for i in range(int((hi - first) / step + 1e-9) + 1)]


def svg(rows, path):
    """Test error against batch-1 latency, both engines, each model labelled where its label
    overlaps no other; error bars: one standard deviation of the runs' test error."""
    w, h, pad = 680, 440, 64
    xs = [r[k] for r in rows for k in ("pvt3_us", "ort_us")]
    x0, x1 = 0, max(xs) * 1.1
    y0, y1 = 0, max(1 - r["accuracy"] + r["std"] for r in rows) * 1.15
    X = lambda v: pad + (v - x0) / (x1 - x0) * (w - 2 * pad)
    Y = lambda v: h - pad - (v - y0) / (y1 - y0) * (h - 2 * pad)
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="11">',
           f'<rect width="{w}" height="{h}" fill="white"/>',
           f'<line x1="{pad}" y1="{h - pad}" x2="{w - pad}" y2="{h - pad}" stroke="black"/>',
           f'<line x1="{pad}" y1="{pad}" x2="{pad}" y2="{h - pad}" stroke="black"/>',
           f'<text x="{w / 2}" y="{h - 20}" text-anchor="middle">batch-1 latency, one thread (µs)</text>',
           f'<text x="16" y="{h / 2}" transform="rotate(-90 16 {h / 2})" text-anchor="middle">test error, mean ± std over the runs</text>',
           f'<circle cx="{w - 190}" cy="20" r="4" fill="#1f77b4"/><text x="{w - 180}" y="24">pvt3 runtime (tract)</text>',
           f'<rect x="{w - 194}" y="32" width="8" height="8" fill="#ff7f0e"/><text x="{w - 180}" y="40">onnxruntime, same file</text>']
    for xv in ticks(x0, x1):
        out.append(f'<line x1="{X(xv)}" y1="{h - pad}" x2="{X(xv)}" y2="{h - pad + 4}" stroke="black"/>')
        out.append(f'<text x="{X(xv)}" y="{h - pad + 16}" text-anchor="middle">{xv:g}</text>')
    for yv in ticks(y0, y1):
        out.append(f'<line x1="{pad - 4}" y1="{Y(yv)}" x2="{pad}" y2="{Y(yv)}" stroke="black"/>')
        out.append(f'<text x="{pad - 6}" y="{Y(yv) + 4}" text-anchor="end">{yv:g}</text>')
    # The markers first, then each label at the first spot beside its markers that overlaps no
    # marker, bar or label placed before it.
    placed = []  # boxes taken: (left, top, right, bottom)
    for r in rows:
        y, xp, xo = Y(1 - r["accuracy"]), X(r["pvt3_us"]), X(r["ort_us"])
        top, bottom = Y(1 - r["accuracy"] + r["std"]), Y(1 - r["accuracy"] - r["std"])
        for x in (xp, xo):
            out.append(f'<line x1="{x}" y1="{top}" x2="{x}" y2="{bottom}" stroke="#888"/>')
            out.extend(f'<line x1="{x - 3}" y1="{v}" x2="{x + 3}" y2="{v}" stroke="#888"/>' for v in (top, bottom))
            placed.append((x - 4, top, x + 4, bottom))
        out.append(f'<line x1="{xo}" y1="{y}" x2="{xp}" y2="{y}" stroke="#bbb"/>')
        out.append(f'<circle cx="{xp}" cy="{y}" r="4" fill="#1f77b4"/>')
        out.append(f'<rect x="{xo - 4}" y="{y - 4}" width="8" height="8" fill="#ff7f0e"/>')
        placed.append((min(xp, xo) - 5, y - 5, max(xp, xo) + 5, y + 5))
    free = lambda b: all(b[2] < p[0] or b[0] > p[2] or b[3] < p[1] or b[1] > p[3] for p in placed)
    for r in rows:
        y, xp, xo = Y(1 - r["accuracy"]), X(r["pvt3_us"]), X(r["ort_us"])
        width = 6.2 * len(r["name"])
        right, left, middle = max(xp, xo) + 8, min(xp, xo) - 8 - width, (xp + xo - width) / 2
        spots = [(right, y + 4), (left, y + 4)] + [(sx, y + dy) for dy in (-9, 17, -22, 30, -35, 43, -48, 56) for sx in (right, middle, left)]
        lx, ly = next(((sx, sy) for sx, sy in spots if free((sx, sy - 10, sx + width, sy + 2))), spots[0])
        placed.append((lx, ly - 10, lx + width, ly + 2))
        out.append(f'<text x="{lx}" y="{ly}">{r["name"]}</text>')
    out.append("</svg>")
    Path(path).write_text("\n".join(out) + "\n")


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--svg", required=True)
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--seconds", type=float, default=1.0)
    p.add_argument("--runner", default="./target/robot/pvt3-run", help="the pvt3-run binary to time")
    p.add_argument("models", nargs="+", help="NAME=DIR[:pruned]: a pvt3 cv directory (its pruned runs with :pruned)")
    a = p.parse_args()
    Path("target/grid").mkdir(parents=True, exist_ok=True)
    rows = []
    for spec in a.models:
        name, where = spec.split("=", 1)
        part = cv_part(where)
        if part is None:
            sys.exit(f"{where}: no cv.json (run its cross-validation first)")
        run, runs = part["run"], len(part["runs"])
        onnx = f"target/grid/{name}.onnx"
        subprocess.run([PVT3, "export", str(run), "-o", onnx], capture_output=True, check=True)
        params, macs, kept = info(str(run))
        rows.append(dict(name=name, runs=runs, seeds=len({r["seed"] for r in part["runs"]}),
                         accuracy=part["mean"], std=part["std"],
                         params=params, macs=macs, kept=kept, onnx=onnx, pvt3=[], ort=[]))
    for i in range(a.rounds):
        for r in rows:
            print(f"round {i + 1}/{a.rounds}: {r['name']}", file=sys.stderr)
            r["pvt3"].append(bench([a.runner, "--bench", r["onnx"], "1", str(a.seconds)]))
            r["ort"].append(bench([sys.executable, "bench/ort_latency.py", r["onnx"], str(a.seconds)]))
    med = lambda xs, k: statistics.median(x[k] for x in xs)
    print("| model | seeds × folds | test accuracy, mean ± std | parameters | multiply-adds | tokens kept | pvt3 batch 1 median / p99 (µs) | pvt3 batch 1, untuned kernels (µs) | pvt3 batch 32 (windows/s) | onnxruntime batch 1 median (µs) | onnxruntime batch 32 (windows/s) | pvt3 / onnxruntime | speed-up over unpruned (pvt3, batch 1) | pvt3 streamed, answer after the last frame, median (µs) |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    base = med(rows[0]["pvt3"], "batch1_median_us")
    for r in rows:
        r["pvt3_us"], r["ort_us"] = med(r["pvt3"], "batch1_median_us"), med(r["ort"], "batch1_median_us")
        print(f"| {r['name']} | {r['seeds']} × {r['runs'] // r['seeds']} | {r['accuracy'] + 1e-12:.4f} ± {r['std']:.4f} | {r['params']:,} | {r['macs'] / 1e6:.2f} M | {r['kept']} | "
              f"{r['pvt3_us']:.0f} / {med(r['pvt3'], 'batch1_p99_us'):.0f} | {med(r['pvt3'], 'batch1_untuned_median_us'):.0f} | "
              f"{med(r['pvt3'], 'batch32_windows_per_second'):.0f} | "
              f"{r['ort_us']:.0f} | {med(r['ort'], 'batch32_windows_per_second'):.0f} | {r['pvt3_us'] / r['ort_us']:.2f} | {base / r['pvt3_us']:.2f}× | "
              f"{end_of_touch(r['pvt3'])} |")
    svg(rows, a.svg)


if __name__ == "__main__":
    main()
