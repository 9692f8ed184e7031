"""Test accuracy against the length of training, from one long cross-validation's metrics: for
each budget of E epochs, every run's test accuracy at the epoch that validation selects among
its first E (the last improvement up to E; `metrics.jsonl` records the test accuracy at each
improvement), mean ± std over the runs and each seed's mean.

    EPOCHS=600 SEEDS=0 bash bench/baselines.sh raec-published-icub
    python3 bench/epochs_curve.py runs/cv-raec-published-icub [STEP]     # a row every STEP (100) epochs

Valid only for a learning rate that does not depend on the run's length (the raec-published row:
constant, no warm-up): then a run's first E epochs are the run of E epochs, and one long run
gives every shorter one.
"""
import json
import statistics
import sys
from pathlib import Path


def selected_test_accuracy(metrics, budget):
    """The test accuracy of the last validation improvement within the first `budget` epochs."""
    chosen = None
    for m in metrics:
        if m["epoch"] <= budget and m["test_accuracy"] is not None:
            chosen = m["test_accuracy"], m["epoch"]
    return chosen


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    out, step = Path(sys.argv[1]), int(sys.argv[2]) if len(sys.argv) > 2 else 100
    runs = sorted(p.parent for p in out.glob("seed*/fold?/metrics.jsonl"))
    if not runs:
        sys.exit(f"{out}: no seed*/fold?/metrics.jsonl (a `pvt3 cv` output directory)")
    metrics = {run: [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines() if line.strip()] for run in runs}
    done = min(len(m) for m in metrics.values())
    lr = {m["lr"] for ms in metrics.values() for m in ms}
    if len(lr) > 1:
        sys.exit(f"{out}: the learning rate varies ({min(lr):g} … {max(lr):g}); a shorter run would not be the first part of a long one")
    print(f"{len(runs)} runs ({', '.join(str(r.relative_to(out)) for r in runs)}), {done} epochs each finished\n")
    print("| epochs | test accuracy, mean ± std | seed means | selected epochs (median) |")
    print("|---:|---:|---|---:|")
    for budget in range(step, done + 1, step):
        picked = {run: selected_test_accuracy(ms, budget) for run, ms in metrics.items()}
        accs = [p[0] for p in picked.values()]
        seeds = sorted({run.parent.name for run in runs})
        means = [statistics.mean(picked[r][0] for r in runs if r.parent.name == s) for s in seeds]
        sd = statistics.stdev(accs) if len(accs) > 1 else 0.0
        print(f"| {budget} | {statistics.mean(accs):.4f} ± {sd:.4f} | {', '.join(f'{m:.4f}' for m in means)} | "
              f"{statistics.median(p[1] for p in picked.values()):.0f} |")


if __name__ == "__main__":
    main()
