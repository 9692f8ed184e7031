"""Stopping rules for provisional answers, compared (docs/anytime.md, "Other rules"). Each rule is
calibrated on a run's validation fold and applied to its test fold, as the trainer calibrates the
rule it ships; the figures are the change in test accuracy against the whole touch (points) and
the mean share of the touch used, mean ± std over the runs.

    bash bench/anytime.sh                                   # the runs, in runs/anytime/
    target/onnx-venv/bin/python bench/stop_rules.py runs/anytime/biotac20-prefix0.5-s{0,1,2} ...

For each run it reads every sample's provisional answers after each token, from
`pvt3 eval RUN --anytime --answers FILE` on the validation fold and on fold 4 (cached in
target/stop_rules/). The rules:

- pvt3 train's: top probability ≥ t with 3 answers in a row agreeing; t the lowest threshold such that
  no threshold above it loses accuracy on the validation fold (trainer/src/anytime.rs; this
  script's figure must equal `pvt3 eval --anytime`'s, which it checks).
- margin: the same with the margin between the two most probable classes.
- agreement calibrated: the agreement length chosen too (2 … 12), the earliest rule whose
  stricter neighbours (higher t, longer agreement) lose nothing either.
- per-class thresholds: one threshold per answered class, each calibrated as the shipped one.
- 0.5-point allowance: the shipped rule calibrated to lose at most 0.5 points on validation.
- pooled over the cross-validation (runs of one `pvt3 cv`, `OUT/seedS/foldK`, or its pruned runs
  `OUT/seedS/foldK/pruned`, given together):
  calibrated once on the validation answers of all its runs (each fold's model on its own
  validation fold; 12 × 200 samples for 3 seeds) and applied to each run's test answers; with no
  loss allowed and 3 agreeing, and as `pvt3 cv` ships it (trainer/src/stopping.rs): a loss of
  0.5 points allowed (a dozen samples, not one) and the agreement length chosen too (the one of
  2 … 12 that stops earliest on those answers). Two stricter calibrations of the same, to see
  whether the test fold's larger loss is the allowance's: no loss allowed, and the loss's
  one-sided 95 % upper bound (its mean plus 1.645 standard errors over the pooled samples)
  within 0.5 points. Where a run carries that rule, this script's
  figure for it must equal `pvt3 eval --anytime`'s, which it checks. The test touches whose
  answer that rule changes against the whole touch (lost or gained) are listed, each with the
  number of runs it happens in (whether the loss is a few touches' or spread) and the classes of
  its three nearest touches outside the test fold by channel levels over the frames read by then
  (what the recordings themselves place that much of it among).
- best threshold on the test fold: not a rule (it looks at the test fold); the most a single
  threshold with 3 agreeing answers could do, within 0.5 points of the whole touch. The classes
  it stops wrongly on (that the whole touch gets right) are listed under the table.
"""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

PVT3 = "./target/release/pvt3"
CACHE = Path("target/stop_rules")
AGREEING = 3


def answers(run, fold):
    """probabilities [n, tokens, classes] and labels of `run` on `fold`, and eval's report."""
    CACHE.mkdir(parents=True, exist_ok=True)
    # Named by the whole path: the runs of a cross-validation are all called foldK.
    path = CACHE / f"{str(Path(run).resolve()).strip('/').replace('/', '_')}-fold{fold}.json"
    report = json.loads(subprocess.run([PVT3, "eval", run, "--anytime", "--json", "--fold", str(fold), "--answers", str(path)],
                                       capture_output=True, text=True, check=True).stdout)
    a = json.loads(path.read_text())
    return np.array(a["probabilities"], dtype=np.float64), np.array(a["labels"]), report


def cross_validation_of(run):
    """The `pvt3 cv` directory of a fold's run (`OUT/seedS/foldK`) or of its pruned run
    (`OUT/seedS/foldK/pruned`), and whether it is the pruned one; None for another run."""
    here = Path(run).resolve()
    fold = here.parent if here.name == "pruned" else here
    if fold.name.startswith("fold") and fold.parent.name.startswith("seed"):
        return fold.parent.parent, fold != here
    return None


class Answers:
    def __init__(self, p, y):
        self.y, self.n, self.tokens = y, p.shape[0], p.shape[1]
        self.cls = p.argmax(-1)
        s = np.sort(p, -1)
        self.score = {"top": s[..., -1], "margin": s[..., -1] - s[..., -2]}
        # run[i, k]: how many answers in a row up to token k name the class of token k.
        self.run = np.ones_like(self.cls)
        for k in range(1, self.tokens):
            self.run[:, k] = np.where(self.cls[:, k] == self.cls[:, k - 1], self.run[:, k - 1] + 1, 1)
        self.full = (self.cls[:, -1] == y).mean()

    def stops(self, kind, thresholds, agreeing):
        """Each sample's answer where it stops: at its first token whose score reaches the
        threshold of its answered class with `agreeing` answers in a row agreeing, and the token."""
        hit = (self.score[kind] >= np.asarray(thresholds)[self.cls]) & (self.run >= agreeing)
        k = np.where(hit.any(1), hit.argmax(1), self.tokens - 1)
        return self.cls[np.arange(self.n), k], k

    def stop(self, kind, thresholds, agreeing):
        """Accuracy and mean share of the touch when each sample stops by the rule."""
        answer, k = self.stops(kind, thresholds, agreeing)
        return (answer == self.y).mean(), (k + 1).mean() / self.tokens

    def wrong_stops(self, kind, thresholds, agreeing):
        """(class, answer) of the samples the rule stops wrongly that the whole touch gets right."""
        answer, _ = self.stops(kind, thresholds, agreeing)
        wrong = (answer != self.y) & (self.cls[:, -1] == self.y)
        return list(zip(self.y[wrong].tolist(), answer[wrong].tolist()))

    def candidates(self, kind):
        return np.concatenate([[1.0], np.unique(self.score[kind])[::-1]])

    def calibrate(self, kind="top", agreeing=AGREEING, allowance=0.0, classes=None, base=None, z=0.0):
        """The lowest threshold (for every class, or only for `classes`, the others at `base`)
        such that none from it up to 1 loses more than `allowance` against the whole touch; with
        `z` > 0, such that the loss's upper bound (its mean plus z standard errors over the
        samples) stays within the allowance."""
        c = self.cls.max() + 1 if base is None else len(base)
        chosen = 1.0
        for t in self.candidates(kind):
            th = np.full(c, t) if base is None else np.where(np.isin(np.arange(c), classes), t, base)
            if z > 0:
                answer, _ = self.stops(kind, th, agreeing)
                d = (self.cls[:, -1] == self.y).astype(float) - (answer == self.y)
                if d.mean() + z * d.std(ddof=1) / np.sqrt(self.n) > allowance + 1e-12:
                    break
            elif self.stop(kind, th, agreeing)[0] < self.full - allowance - 1e-12:
                break
            chosen = t
        return chosen


def rules(val, test, confusions):
    """(name, test accuracy change in points, share) of each rule calibrated on `val`; adds the
    wrong stops of the best test-fold threshold to `confusions`."""
    c = max(val.cls.max(), test.cls.max()) + 1
    out = []

    def apply(name, kind, thresholds, agreeing):
        acc, share = test.stop(kind, np.broadcast_to(thresholds, (c,)), agreeing)
        out.append((name, 100 * (acc - test.full), share))

    apply("pvt3 train's (its own validation fold)", "top", val.calibrate(), AGREEING)
    apply("margin", "margin", val.calibrate("margin"), AGREEING)
    lengths = [2, 3, 4, 6, 8, 12]
    t = {a: val.calibrate(agreeing=a) for a in lengths}
    robust = [(a, max(t[b] for b in lengths[i:])) for i, a in enumerate(lengths)]
    a, th = min(robust, key=lambda r: val.stop("top", np.full(c, r[1]), r[0])[1])
    apply("agreement calibrated", "top", th, a)
    per_class = np.ones(c)
    for k in range(c):
        per_class[k] = val.calibrate(classes=[k], base=per_class)
    apply("per-class thresholds", "top", per_class, AGREEING)
    apply("0.5-point allowance", "top", val.calibrate(allowance=0.005), AGREEING)
    best = min((test.stop("top", np.full(c, t), AGREEING)[1], t) for t in test.candidates("top")
               if test.stop("top", np.full(c, t), AGREEING)[0] >= test.full - 0.005 - 1e-12)
    apply("best threshold on the test fold (not a rule)", "top", best[1], AGREEING)
    confusions.extend(test.wrong_stops("top", np.full(c, best[1]), AGREEING))
    return out


LENGTHS = [2, 3, 4, 5, 6, 8, 12]  # trainer/src/anytime.rs, AGREEMENT_LENGTHS
POOLED_ALLOWANCE = 0.005          # and POOLED_ALLOWANCE
Z95 = 1.645                       # a one-sided 95 % bound, normal approximation


def pooled_rules(group):
    """(name, (threshold, agreeing), [(change, share) per run]) of the rules calibrated on the
    validation answers of all runs of `group` together, each applied to each run's test answers."""
    pv = np.concatenate([v[0] for v, _ in group])
    pooled = Answers(pv, np.concatenate([v[1] for v, _ in group]))
    c = pv.shape[-1]
    def earliest(allowance, z=0.0):
        """(share, agreeing, threshold) of the agreement length that stops earliest."""
        return min(((pooled.stop("top", np.full(c, t), a)[1], a, t) for a in LENGTHS if a <= pooled.tokens
                    for t in [pooled.calibrate(agreeing=a, allowance=allowance, z=z)]), key=lambda r: r[0])
    strict, bound, shipped = earliest(0.0), earliest(POOLED_ALLOWANCE, Z95), earliest(POOLED_ALLOWANCE)
    out = []
    for name, t, a in [("pooled over the cross-validation, 3 agreeing, no loss", pooled.calibrate(), AGREEING),
                       ("pooled, no loss, agreement chosen", strict[2], strict[1]),
                       ("pooled, the loss's one-sided 95 % bound within 0.5 points, agreement chosen", bound[2], bound[1]),
                       ("pooled over the cross-validation, 0.5 points, agreement chosen (pvt3 cv's)", shipped[2], shipped[1])]:
        out.append((name, (t, a), [(100 * (acc - test.full), share)
                                   for _, test in group for acc, share in [test.stop("top", np.full(c, t), a)]]))
    return out


def nearest_by_levels(data, touches, k=3, shares=None):
    """The classes of the k nearest non-test touches of each test touch in `touches`, by
    standardised channel levels: each channel's mean over the touch's first `shares[j]` of its
    frames for the j-th touch (the whole touch by default)."""
    d = np.load(data)
    x, y, fold = d["x"], d["y"], d["fold"]
    x = x.reshape(len(x), -1, x.shape[-1]).astype(np.float64)
    rest, test = fold != 4, np.flatnonzero(fold == 4)
    levels_over = {}  # frames read -> standardised levels of every touch

    def levels(frames):
        if frames not in levels_over:
            v = x[..., :frames].mean(-1)
            levels_over[frames] = (v - v[rest].mean(0)) / (v[rest].std(0) + 1e-9)
        return levels_over[frames]

    out = []
    for i, share in zip(touches, np.ones(len(touches)) if shares is None else shares):
        v = levels(max(1, round(share * x.shape[-1])))
        distance = ((v[rest] - v[test[i]]) ** 2).sum(1)
        out.append(y[rest][np.argsort(distance)[:k]])
    return out


def print_changed_touches(cv, tests, classes, threshold, agreeing, data):
    """The test touches whose answer pvt3 cv's rule changes against the whole touch, over the runs
    of `cv` (each run's `Answers` on the same test fold, in the same order, of `classes` classes):
    where the whole touch is right and the stop wrong (lost) or the other way round (gained), in
    how many runs, at what share of the touch and with which answer; and the classes of the three
    nearest touches outside the test fold in `data` by channel levels over the frames read there."""
    changed = {}
    for test in tests:
        answer, k = test.stops("top", np.full(classes, threshold), agreeing)
        full_right, stop_right = test.cls[:, -1] == test.y, answer == test.y
        for i in np.where(full_right != stop_right)[0]:
            c = changed.setdefault(int(i), {"class": int(test.y[i]), "lost": bool(full_right[i]), "answers": [], "shares": []})
            c["answers"].append(int(answer[i] if full_right[i] else test.cls[i, -1]))
            c["shares"].append((k[i] + 1) / test.tokens)
    print(f"{cv}: test touches pvt3 cv's rule changes against the whole touch, over {len(tests)} runs "
          f"(the classes of the 3 nearest non-test touches in {data} by channel levels over the frames read):", file=sys.stderr)
    touches = sorted(changed, key=lambda i: (-len(changed[i]["shares"]), i))
    shares = [float(np.mean(changed[i]["shares"])) for i in touches]
    for i, share, near in zip(touches, shares, nearest_by_levels(data, touches, shares=shares)):
        c, runs = changed[i], len(changed[i]["shares"])
        answers = ", ".join(f"{b} × {c['answers'].count(b)}" for b in sorted(set(c["answers"])))
        how = f"stopped as {answers}" if c["lost"] else f"right at the stop, the whole touch answers {answers}"
        print(f"  touch {i} (class {c['class']}): {'lost' if c['lost'] else 'gained'} in {runs} run{'s' * (runs > 1)}, "
              f"{how}, at {100 * share:.0f} % of the touch; nearest there: {', '.join(map(str, near))}", file=sys.stderr)


def check(run, row, report):
    """This script's figures for the rule `run` carries must be `pvt3 eval --anytime`'s."""
    change, share = row
    shipped = report["stopping"]
    if abs(share - shipped["mean_share"]) > 1e-9 or abs(change / 100 - (shipped["accuracy"] - shipped["full_accuracy"])) > 1e-9:
        sys.exit(f"{run}: the rule it carries gives {change:+.2f} points at {share:.4f} here, not pvt3 eval's ({shipped})")


def main():
    runs = sys.argv[1:]
    if not runs:
        sys.exit(__doc__)
    table, confusions = {}, []
    cv_of = {}  # a cv's directory -> [((p, y) of validation, test Answers, eval's report)] of its runs
    for run in runs:
        val_fold = json.loads(Path(run, "model", "provenance.json").read_text())["val_fold"]
        pv, yv, _ = answers(run, val_fold)
        pt, yt, report = answers(run, 4)
        val, test = Answers(pv, yv), Answers(pt, yt)
        # A fold's run, or its pruned run, pooled with its own kind.
        if found := cross_validation_of(run):
            cv, pruned = found
            kind = f"{cv}" + (" (pruned runs)" if pruned else "")
            cv_of.setdefault(kind, []).append(((pv, yv), test, report, run))
        results = rules(val, test, confusions)
        if report["calibrated"].get("calibrated_on", "validation_fold") == "validation_fold":
            check(run, results[0][1:], report)
        for name, change, share in results:
            table.setdefault(name, []).append((change, share))
        print(f"{run}: " + "; ".join(f"{n} {c:+.1f} @ {s:.2f}" for n, c, s in results), file=sys.stderr)
    for cv, group in cv_of.items():
        if len(group) > 1:
            pooled = pooled_rules([(g[0], g[1]) for g in group])
            for name, (t, a), rows in pooled:
                table.setdefault(name, []).extend(rows)
                print(f"{cv}: {name} (≥ {t:.4f}, {a} agreeing): " + "; ".join(f"{c:+.1f} @ {s:.2f}" for c, s in rows), file=sys.stderr)
            (t, a), cv_rule_rows = pooled[-1][1:]  # pvt3 cv's rule, the last of pooled_rules
            for (_, _, report, run), row in zip(group, cv_rule_rows):
                if report["calibrated"].get("calibrated_on", "validation_fold") != "validation_fold":
                    check(run, row, report)
            data = json.loads(Path(group[0][3], "model", "provenance.json").read_text())["data"]
            print_changed_touches(cv, [g[1] for g in group], group[0][0][0].shape[-1], t, a, data)
    print(f"| rule ({len(runs)} runs) | test accuracy change (points) | share of the touch used (%) |")
    print("|---|---:|---:|")
    best = [n for n in table if n.startswith("best")]
    for name, rows in sorted(table.items(), key=lambda kv: kv[0] in best):
        r = np.array(rows)
        sd = lambda v: v.std(ddof=1) if len(v) > 1 else 0.0
        print(f"| {name} | {r[:, 0].mean():+.1f} ± {sd(r[:, 0]):.1f} | {100 * r[:, 1].mean():.0f} ± {100 * sd(r[:, 1]):.0f} |")
    pairs = sorted({p: confusions.count(p) for p in confusions}.items(), key=lambda kv: -kv[1])
    print("\nwrong stops of the best test-fold threshold, (class → answer) × count: "
          + ", ".join(f"{a} → {b} × {n}" for (a, b), n in pairs[:8]))


if __name__ == "__main__":
    main()
