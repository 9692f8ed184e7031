"""The tables of docs/robustness.md from the runs of `bash bench/robustness.sh`: for every variant
(a folder under the runs' root, as VARIANT named it) and row (a held-out condition, or `random`),
the mean ± std test accuracy over all runs (seeds × validation folds) on the held-out touches,
the 95 % interval of the mean (Student's t over the seeds' means, as `pvt3 cv` computes it), and
the gap to the random split (the variant's own, else the `plain` variant's); then, for every row
that several variants ran, one table of them side by side; last, a variant's runs pooled with
those of more seeds (a variant NAME-seeds), and each variant against `plain` and against the
variant its name extends (`extrapolate1-levels` against `extrapolate1`), seed by seed, on a row
both ran by the headline protocol (three seeds or more, each seed's four validation folds).

    python3 bench/robustness_report.py [ROOT]          # ROOT: target/robustness by default

A row whose cross-validation has not finished is shown as `–`; one with fewer than three seeds
says how many it has.
"""
import json
import statistics
import sys
from pathlib import Path

ROWS = ["random", "speeds-between", "speeds-beyond", "forces-unseen", "direction-forward", "direction-back"]
ROWS += [f"speed-{v}" for v in (10, 20, 50, 100, 120, 150)] + [f"force-{f}" for f in (120, 150, 180, 210, 250)]


def summary(run_dir):
    path = run_dir / "cv.json"
    return json.loads(path.read_text()) if path.exists() else None


def cell(s, random_mean):
    if s is None:
        return "–"
    text = f"{s['mean_test_accuracy']:.4f} ± {s['std_test_accuracy']:.4f}"
    interval = s.get("ci95_test_accuracy")
    if interval:
        text += f" [{interval[0]:.3f}, {interval[1]:.3f}]"
    if len(s["seeds"]) < 3:
        text += f" ({len(s['seeds'])} seed{'s' if len(s['seeds']) > 1 else ''})"
    if random_mean is not None and s.get("held_out"):
        text += f", {100 * (s['mean_test_accuracy'] - random_mean):+.1f} pts"
    return text


def main():
    root = Path(sys.argv[1] if len(sys.argv) > 1 else "target/robustness")
    variants = sorted((d for d in root.iterdir() if d.is_dir()), key=lambda d: (d.name != "plain", d.name))
    if not variants:
        sys.exit(f"{root}: no runs (bash bench/robustness.sh FABRICSLIDE first)")
    # One fabric's other direction (direction-forward-Canvas, …) is a row of its own.
    fabric_rows = sorted({d.name for v in variants for d in v.glob("direction-*-*") if d.is_dir()})
    rows_run = ROWS + fabric_rows
    found = {v.name: {row: summary(v / row) for row in rows_run if (v / row).is_dir()} for v in variants}
    plain_random = (found.get("plain", {}).get("random") or {}).get("mean_test_accuracy")
    for variant, rows in found.items():
        if len(rows) < 2:
            continue
        random = rows.get("random")
        random_mean = random["mean_test_accuracy"] if random else plain_random
        print(f"\n### {variant}\n")
        print("| test touches | held out | accuracy, mean ± std [95 % interval], gap to random | runs |")
        print("|---|---|---|---:|")
        for row, s in rows.items():
            held = s.get("held_out") if s else None
            held_text = f"{held['condition']} = {', '.join(held['levels'])}" if held else "nothing (stratified)"
            if held and held.get("class"):
                held_text += f" of {held['class']}"
            print(f"| {row} | {held_text} | {cell(s, random_mean)} | {len(s['runs']) if s else 0} |")
    for row in rows_run:
        ran = [(variant, rows[row]) for variant, rows in found.items() if row in rows]
        if len(ran) < 2:
            continue
        print(f"\n### {row}, every variant\n")
        print("| variant | accuracy, mean ± std [95 % interval], gap to random | runs |")
        print("|---|---|---:|")
        for variant, s in ran:
            random = found[variant].get("random")
            random_mean = random["mean_test_accuracy"] if random else plain_random
            print(f"| {variant} | {cell(s, random_mean)} | {len(s['runs']) if s else 0} |")
    more_seeds(found)


def t_975(df):
    """The two-sided 95 % quantile of Student's t with `df` degrees of freedom, as `pvt3 cv`
    computes it (trainer/src/cv.rs, `t_975`): tabled to 30, then the Cornish–Fisher expansion."""
    table = [12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160, 2.145, 2.131,
             2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056, 2.052, 2.048, 2.045, 2.042]
    if df <= 30:
        return table[df - 1]
    z = 1.959964
    return z + (z**3 + z) / (4 * df) + (5 * z**5 + 16 * z**3 + 3 * z) / (96 * df * df)


def interval(values):
    """The mean of `values` (one per seed) and its 95 % interval, Student's t."""
    mean = statistics.mean(values)
    half = t_975(len(values) - 1) * statistics.stdev(values) / len(values) ** 0.5
    return mean, mean - half, mean + half


def seed_means(runs):
    seeds = sorted({r["seed"] for r in runs})
    return {s: statistics.mean(r["test_accuracy"] for r in runs if r["seed"] == s) for s in seeds}


def whole_seeds(runs):
    """Each seed's mean over its runs, for the seeds that ran all four validation folds."""
    folds = {}
    for r in runs:
        folds.setdefault(r["seed"], set()).add(r["val_fold"])
    return {s: m for s, m in seed_means(runs).items() if len(folds[s]) == 4}


def more_seeds(found):
    """A variant `NAME-seeds` holds more seeds of `NAME` (SEEDS=3,4 VARIANT=NAME-seeds): each row
    both ran, with all their runs pooled (mean ± std over the runs, each seed's mean and the 95 %
    interval over them). Then every variant against `plain` and against the variant its name
    extends, on the seeds both ran with all four folds (three or more): the difference of each
    seed's mean, and its mean's 95 % interval (paired seeds)."""
    pooled = {}
    for variant, rows in found.items():
        if variant.endswith("-seeds"):
            continue
        extra = found.get(f"{variant}-seeds", {})
        for row in (r for r in rows if rows[r]):
            runs = rows[row]["runs"] + (extra[row]["runs"] if extra.get(row) else [])
            pooled[variant, row] = runs
            if not extra.get(row):
                continue
            acc = [r["test_accuracy"] for r in runs]
            means = seed_means(runs)
            _, low, high = interval(list(means.values()))
            print(f"\n{variant} {row}, seeds {', '.join(map(str, means))} pooled: "
                  f"{statistics.mean(acc):.4f} ± {statistics.stdev(acc):.4f} [{low:.4f}, {high:.4f}] over {len(acc)} runs; "
                  f"seed means {', '.join(f'{m:.4f}' for m in means.values())}")
    for (variant, row), runs in pooled.items():
        extended = [v for v, r in pooled if r == row and v != variant and variant.startswith(f"{v}-")]
        for other in ["plain"] * (variant != "plain") + extended:
            base = pooled.get((other, row))
            if base is None:
                continue
            mine, theirs = whole_seeds(runs), whole_seeds(base)
            common = [s for s in mine if s in theirs]
            if len(common) < 3:
                continue
            diffs = [100 * (mine[s] - theirs[s]) for s in common]
            mean, low, high = interval(diffs)
            print(f"\n{variant} against {other}, {row}, seeds {', '.join(map(str, common))}: "
                  f"{', '.join(f'{d:+.1f}' for d in diffs)} pts; mean {mean:+.1f} [{low:+.1f}, {high:+.1f}]")


if __name__ == "__main__":
    main()
