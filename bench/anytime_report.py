"""The figures of docs/anytime.md from bench/anytime.sh's measurements: accuracy against the share
of the touch (mean ± std over seeds), the calibrated stopping rule on the test fold, the cost of a
provisional answer, and docs/anytime.svg. Rewrites docs/anytime.md below its figures marker.

    python3 bench/anytime_report.py RESULTS.jsonl COSTS.jsonl P "SEEDS"
"""
import json
import statistics
import sys

results_path, costs_path, p, seeds = sys.argv[1:]
rows = [json.loads(line) for line in open(results_path)]
costs = [json.loads(line) for line in open(costs_path)]
names = {d: n for d, n in {"icub20": "iCub-20", "biotac20": "BioTac-20"}.items() if any(r["data"] == d for r in rows)}
variants = ["whole", f"prefix{p}"]
labels = {"whole": "whole windows", f"prefix{p}": f"`--prefix-training {p}`"}


def stats(values):
    m = statistics.mean(values)
    s = statistics.stdev(values) if len(values) > 1 else 0.0
    return m, s


def pm(values, scale=100, digits=1):
    m, s = stats(values)
    return f"{m * scale:.{digits}f} ± {s * scale:.{digits}f}"


out = [f"Measured by `bash bench/anytime.sh` (seeds {seeds.replace(' ', ', ')}; `P={p}`): one run per seed, "
       "validation fold 0, test fold 4, 100 epochs; every figure is on the test fold, mean ± std over the seeds "
       f"({len(seeds.split())} runs each), in %.\n"]
out.append("Accuracy from the first part of each touch (a provisional answer after that share of its temporal tokens):\n")
shares = [c["share"] for c in rows[0]["curve"]]
out.append("| data set | training | " + " | ".join(f"{s:.0%}" for s in shares) + " |")
out.append("|---|---|" + "---:|" * len(shares))
for data in names:
    for v in variants:
        rs = [r for r in rows if r["data"] == data and r["variant"] == v]
        if not rs:
            continue
        cells = [pm([r["curve"][i]["accuracy"] for r in rs]) for i in range(len(shares))]
        out.append(f"| {names[data]} | {labels[v]} | " + " | ".join(cells) + " |")

out.append("\nThe stopping rule (stop at the first token whose top probability reaches the threshold with the answers of "
           "three tokens in a row agreeing; the threshold calibrated on the validation fold to lose nothing there), applied "
           "to the test fold:\n")
out.append("| data set | training | threshold (per seed) | accuracy, whole touch | accuracy, stopped | change (points) | share of the touch used |")
out.append("|---|---|---|---:|---:|---:|---:|")
verdict = []
for data in names:
    for v in variants:
        rs = [r for r in rows if r["data"] == data and r["variant"] == v]
        if not rs:
            continue
        full = [r["stopping"]["full_accuracy"] for r in rs]
        stopped = [r["stopping"]["accuracy"] for r in rs]
        share = [r["stopping"]["mean_share"] for r in rs]
        change = [s - f for s, f in zip(stopped, full)]
        thresholds = ", ".join(f"{r['calibrated']['rule']['top_probability']:.3f}" for r in rs)
        out.append(f"| {names[data]} | {labels[v]} | {thresholds} | {pm(full)} | {pm(stopped)} | {pm(change)} | {pm(share, digits=0)} |")
        if v != "whole":
            m_change, m_share = statistics.mean(change), statistics.mean(share)
            verdict.append((names[data], m_change, m_share))

out.append("\nThe goal (accuracy within 0.5 points of the whole window, ≤ 40 % of the touch on average), prefix-trained, "
           "by each run's own rule (`pvt3 train`'s, one validation fold; `pvt3 cv`'s rule, calibrated on a whole "
           "cross-validation, is measured in \"Calibrated on a cross-validation\" above): " +
           "; ".join(f"{n}: {c * 100:+.1f} points at {s:.0%} of the touch ({'met' if c >= -0.005 and s <= 0.40 else 'not met'})"
                     for n, c, s in verdict) + ".")

out.append("\nThe cost of a provisional answer in the runtime (`pvt3-run --bench`, one thread, median µs; it runs the "
           "temporal stage at full length with the tokens to come masked, so it costs what the end of a touch costs):\n")
out.append("| file | peek at 10 % | at 50 % | at 100 % | end of touch (`finish`) |")
out.append("|---|---:|---:|---:|---:|")
for c in costs:
    peek = c["stream_peek_us"]
    out.append(f"| `{c['model']}` | {peek['stream_peek_10pct_median_us']:.0f} | {peek['stream_peek_50pct_median_us']:.0f} | "
               f"{peek['stream_peek_100pct_median_us']:.0f} | {c['stream_end_of_touch_median_us']:.0f} |")

# The plot: accuracy against the share of the touch, one panel per data set, error bars over seeds,
# the stopping rule's (share, accuracy) as a marker.
W, H, PAD = 360, 260, 46
colors = {"whole": "#888888", f"prefix{p}": "#1f6fb4"}
svg = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{len(names) * W}" height="{H + 40}" font-family="sans-serif" font-size="11">']
for panel, data in enumerate(names):
    x0 = panel * W
    rs_all = [r for r in rows if r["data"] == data]
    lo = min(0.5, min(c["accuracy"] for r in rs_all for c in r["curve"]) - 0.02)
    lo = max(0.0, int(lo * 20) / 20)
    fx = lambda s: x0 + PAD + (W - PAD - 14) * s
    fy = lambda a: 20 + (H - 50) * (1 - (a - lo) / (1 - lo))
    svg.append(f'<text x="{x0 + W / 2}" y="14" text-anchor="middle" font-weight="bold">{names[data]}</text>')
    svg.append(f'<line x1="{fx(0)}" y1="{fy(lo)}" x2="{fx(1)}" y2="{fy(lo)}" stroke="black"/>')
    svg.append(f'<line x1="{fx(0)}" y1="{fy(lo)}" x2="{fx(0)}" y2="{fy(1)}" stroke="black"/>')
    for s in [0, 0.2, 0.4, 0.6, 0.8, 1.0]:
        svg.append(f'<text x="{fx(s)}" y="{fy(lo) + 14}" text-anchor="middle">{s:.0%}</text>')
    a = lo
    while a <= 1.0001:
        svg.append(f'<line x1="{fx(0) - 3}" y1="{fy(a)}" x2="{fx(1)}" y2="{fy(a)}" stroke="#eeeeee"/>')
        svg.append(f'<text x="{fx(0) - 5}" y="{fy(a) + 4}" text-anchor="end">{a:.2f}</text>')
        a += 0.1 if 1 - lo > 0.3 else 0.05
    svg.append(f'<text x="{x0 + W / 2}" y="{H + 8}" text-anchor="middle">share of the touch</text>')
    svg.append(f'<text x="{x0 + 12}" y="{fy((1 + lo) / 2)}" transform="rotate(-90 {x0 + 12} {fy((1 + lo) / 2)})" text-anchor="middle">test accuracy</text>')
    for k, v in enumerate(variants):
        rs = [r for r in rs_all if r["variant"] == v]
        if not rs:
            continue
        pts = []
        for i, s in enumerate(shares):
            m, sd = stats([r["curve"][i]["accuracy"] for r in rs])
            pts.append((fx(s), fy(m)))
            svg.append(f'<line x1="{fx(s)}" y1="{fy(m - sd)}" x2="{fx(s)}" y2="{fy(m + sd)}" stroke="{colors[v]}"/>')
        svg.append(f'<polyline fill="none" stroke="{colors[v]}" stroke-width="1.5" points="{" ".join(f"{x:.1f},{y:.1f}" for x, y in pts)}"/>')
        ms, ma = statistics.mean(r["stopping"]["mean_share"] for r in rs), statistics.mean(r["stopping"]["accuracy"] for r in rs)
        svg.append(f'<circle cx="{fx(ms):.1f}" cy="{fy(ma):.1f}" r="4" fill="none" stroke="{colors[v]}" stroke-width="2"/>')
        svg.append(f'<line x1="{x0 + W - 150}" y1="{fy(lo) - 30 - 14 * k}" x2="{x0 + W - 135}" y2="{fy(lo) - 30 - 14 * k}" stroke="{colors[v]}" stroke-width="2"/>')
        svg.append(f'<text x="{x0 + W - 130}" y="{fy(lo) - 26 - 14 * k}">{labels[v].strip("`")}</text>')
    svg.append(f'<text x="{x0 + W - 150}" y="{fy(lo) - 58}">○ stopping rule (mean)</text>')
svg.append("</svg>")
open("docs/anytime.svg", "w").write("\n".join(svg) + "\n")

text = "\n".join(out) + "\n\n![accuracy against the share of the touch](anytime.svg)\n"
doc = open("docs/anytime.md").read()
marker = "<!-- figures: bash bench/anytime.sh -->\n"
open("docs/anytime.md", "w").write(doc.split(marker)[0] + marker + "\n" + text)
print(text)
