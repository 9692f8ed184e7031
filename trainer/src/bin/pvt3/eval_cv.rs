//! `pvt3 eval CV_DIR`: every finished run of a cross-validation on one fold (by default the test
//! fold), their answers together: the runs' accuracy as mean ± std and the confusion matrix of
//! all their answers, or with `--anytime` what the stopping rule `pvt3 cv` wrote into the runs
//! does, run by run (mean ± std, the figures docs/anytime.md gives) and pooled (drawn), with the
//! touches whose answer at the stop differs from the whole touch's in the most runs.
//! `--pruned` reads each run's pruned model instead.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{bail, Result};
use pvt3_trainer::anytime::{self, Prefixes};
use pvt3_trainer::cv::mean_std;
use pvt3_trainer::evaluate::evaluate;
use pvt3_trainer::run_dir::{CrossValidation, Run, CV_SUMMARY};

use crate::eval::{by_condition, draw_anytime, print_tenths, report_classes, report_levels, EvalArgs, Folds, Loaded, ANYTIME, CONFUSION};

/// Whether `pvt3 eval`'s directory is a cross-validation's (it holds cv.json).
pub fn applies(a: &EvalArgs) -> bool {
    a.checkpoint.join(CV_SUMMARY).exists()
}

pub fn run(a: &EvalArgs) -> Result<()> {
    if a.answers.is_some() || a.json {
        bail!("--answers and --json read one checkpoint; {} is a cross-validation: give one of its runs", a.checkpoint.display());
    }
    let runs = finished(a)?;
    let what = if a.pruned { "pruned runs" } else { "runs" };
    if a.anytime {
        return anytime_report(a, &runs, what);
    }
    let (mut classes, mut labels, mut predictions, mut accuracies) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut touches, mut conditions) = (Vec::new(), Vec::new());
    for dir in &runs {
        let run = load(dir, a, &mut classes)?;
        let e = evaluate(&run.model, &run.samples())?;
        accuracies.push(e.accuracy);
        touches.extend(&run.indices);
        conditions = run.data.conditions;
        labels.extend(e.labels);
        predictions.extend(e.predictions);
    }
    let (dir, fold, n) = (a.checkpoint.display(), a.fold, runs.len());
    let (mean, std) = mean_std(&accuracies);
    println!("{n} {what} of {dir}, fold {fold}: accuracy {mean:.4} ± {std:.4} (mean ± std over the runs)");
    println!("their {} answers together:", labels.len());
    let right = labels.iter().zip(&predictions).filter(|(l, p)| l == p).count() as f64 / labels.len() as f64;
    let title = format!("{dir}: {n} {what}, fold {fold}, {} answers, accuracy {right:.4}", labels.len());
    report_levels(&by_condition(&conditions, &touches, &labels, &predictions));
    report_classes(&classes, &labels, &predictions, &title, &a.picture_of(CONFUSION))
}

/// The run in `dir` on the fold asked for; its classes must be those of the runs before it
/// (`classes`, empty before the first).
fn load(dir: &Path, a: &EvalArgs, classes: &mut Vec<String>) -> Result<Loaded> {
    let run = Loaded::new(dir, a.data.as_deref(), a.fold)?;
    if classes.is_empty() {
        classes.clone_from(&run.meta.classes);
    } else if run.meta.classes != *classes {
        bail!("{} answers other classes than the runs before it", dir.display());
    }
    Ok(run)
}

/// The checkpoints to read: each finished run of the cross-validation, or its pruned successor;
/// the others are named.
fn finished(a: &EvalArgs) -> Result<Vec<PathBuf>> {
    let mut found = Vec::new();
    for (_, _, dir) in CrossValidation(&a.checkpoint).runs()? {
        let net = if a.pruned { Run(&dir).pruned() } else { dir };
        match Run(&net).result().exists() {
            true => found.push(net),
            false => println!("not finished, not counted: {}", net.display()),
        }
    }
    if found.is_empty() {
        let which = if a.pruned { "seed*/fold*/pruned/result.json" } else { "seed*/fold*/result.json" };
        bail!("{} holds no finished run to evaluate ({which})", a.checkpoint.display());
    }
    Ok(found)
}

/// `--anytime`: each run's provisional answers stopped by the rule it carries (`pvt3 cv` wrote
/// the same into every run), the change against its whole touch as mean ± std over the runs,
/// and all the runs' answers together, printed and drawn.
fn anytime_report(a: &EvalArgs, runs: &[PathBuf], what: &str) -> Result<()> {
    let (mut classes, mut parts, mut changes, mut shares) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut rule, mut differing) = (None, Differing::default());
    for dir in runs {
        let run = load(dir, a, &mut classes)?;
        let Some(stopping) = &run.meta.provenance.stopping else {
            bail!(
                "{} carries no stopping rule (trained before there was one): pvt3 cv --report {} writes one",
                dir.display(),
                a.checkpoint.display()
            );
        };
        match rule {
            None => rule = Some(stopping.clone()),
            Some(ref first) if first.rule != stopping.rule => {
                bail!(
                    "{} carries another stopping rule than {}: pvt3 cv --report {} writes one into all",
                    dir.display(),
                    runs[0].display(),
                    a.checkpoint.display()
                )
            }
            Some(_) => {}
        }
        let samples = run.samples();
        let prefixes = anytime::prefixes(run.model.pvt3("pvt3 eval --anytime")?, &samples)?;
        let here = prefixes.stop_by(stopping.rule);
        changes.push(100.0 * (here.accuracy - here.full_accuracy));
        shares.push(100.0 * here.mean_share);
        differing.add(&run.indices, &samples.touches, &prefixes, stopping.rule);
        parts.push(prefixes);
    }
    let calibrated = rule.expect("at least one run");
    let pooled = Prefixes::pooled(parts)?;
    let (dir, fold, n) = (a.checkpoint.display(), a.fold, runs.len());
    println!(
        "provisional answers of {n} {what} of {dir} on fold {fold}, {} answers, {} temporal tokens per touch",
        pooled.labels.len(),
        pooled.tokens
    );
    print_tenths(&pooled.tenths());
    println!("stopping rule: {}", calibrated.rule);
    let ((change, change_std), (share, share_std)) = (mean_std(&changes), mean_std(&shares));
    println!("here, run by run: {change:+.1} ± {change_std:.1} points against the whole touch, at {share:.0} ± {share_std:.0} % of the touch (mean ± std over the runs)");
    differing.print(&classes, n, fold);
    let picture = a.picture_of(ANYTIME);
    draw_anytime(&picture, &format!("{dir}: {n} {what}, fold {fold}"), &pooled, calibrated.rule)?;
    println!("drew {}", picture.display());
    Ok(())
}

/// The samples whose answer at the rule's stop differs from the whole touch's, over the runs:
/// by touch of the data set and window, and whether the stop's answer is the right one.
#[derive(Default)]
struct Differing(BTreeMap<(usize, usize, bool), Differs>);

#[derive(Default)]
struct Differs {
    label: u32,
    /// Its place among the fold's touches, where it is the same in every run (seeds that draw
    /// their own folds place it differently).
    place: Option<usize>,
    runs: usize,
    /// The share of the touch read at the stop, summed over the runs.
    read: f64,
    /// The wrong answers (at the stop, or at the end), and how often.
    answers: BTreeMap<u32, usize>,
}

impl Differing {
    /// One run's: `touches` numbers each sample's touch in the order of `indices`, the touches'
    /// places in the data set.
    fn add(&mut self, indices: &[usize], touches: &[usize], prefixes: &Prefixes, rule: pvt3_format::StopRule) {
        let (tokens, mut window) = (prefixes.tokens, 0);
        for (i, &(k, right)) in prefixes.stops(rule).iter().enumerate() {
            // A touch's windows come together: its first is window 0.
            window = if i > 0 && touches[i - 1] == touches[i] { window + 1 } else { 0 };
            let label = prefixes.labels[i];
            if right == (prefixes.class[i][tokens - 1] == label) {
                continue;
            }
            let entry = self.0.entry((indices[touches[i]], window, right)).or_default();
            entry.place = match entry.runs {
                0 => Some(touches[i]),
                _ => entry.place.filter(|p| *p == touches[i]),
            };
            entry.label = label;
            entry.runs += 1;
            entry.read += k as f64 / tokens as f64;
            let wrong = if right { prefixes.class[i][tokens - 1] } else { prefixes.class[i][k - 1] };
            *entry.answers.entry(wrong).or_default() += 1;
        }
    }

    /// The ten that differ in the most runs.
    fn print(&self, classes: &[String], runs: usize, fold: Folds) {
        if self.0.is_empty() {
            println!("in every run the rule's answers are the whole touch's");
            return;
        }
        let mut rows: Vec<_> = self.0.iter().collect();
        rows.sort_by_key(|(key, d)| (std::cmp::Reverse(d.runs), **key));
        println!("where the rule's answer differs from the whole touch's, in the most of the {runs} runs (fold {fold}):");
        for ((touch, window, right), d) in rows.iter().take(10) {
            let answers: Vec<String> = d.answers.iter().map(|(c, n)| format!("{} × {n}", classes[*c as usize])).collect();
            let verdict = match right {
                false => format!("wrong at the stop ({}), right at the end", answers.join(", ")),
                true => format!("right at the stop, wrong at the end ({})", answers.join(", ")),
            };
            let window = if *window > 0 { format!(", window {window}") } else { String::new() };
            let place = d.place.map_or(String::new(), |p| format!("no. {p} of fold {fold}, "));
            println!(
                "  touch {touch} of the data set{window} ({place}{}): {verdict}, in {} run{}, at {:.0} % of the touch",
                classes[d.label as usize],
                d.runs,
                if d.runs == 1 { "" } else { "s" },
                100.0 * d.read / d.runs as f64
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three touches, the second read as two windows; under a rule of top probability ≥ 0.8 with
    /// two answers agreeing the first touch stops wrongly, the second's second window stops
    /// rightly where its whole window is wrong, the third never stops.
    #[test]
    fn the_samples_whose_stop_differs_are_counted_by_touch_and_window_over_runs() {
        let prefixes = Prefixes {
            top: vec![vec![0.9, 0.9, 0.6, 0.7], vec![0.5, 0.5, 0.5, 0.5], vec![0.9, 0.9, 0.9, 0.9], vec![0.3, 0.5, 0.6, 0.7]],
            class: vec![vec![2, 2, 1, 1], vec![0, 0, 0, 0], vec![1, 1, 1, 3], vec![1, 2, 2, 2]],
            labels: vec![1, 1, 1, 2],
            tokens: 4,
        };
        let rule = pvt3_format::StopRule { top_probability: 0.8, agreeing: 2 };
        let mut differing = Differing::default();
        for _ in 0..2 {
            differing.add(&[10, 20, 30], &[0, 1, 1, 2], &prefixes, rule);
        }
        let found: Vec<_> = differing.0.iter().map(|(key, d)| (*key, d.place, d.runs, d.read, d.answers.clone())).collect();
        assert_eq!(
            found,
            vec![((10, 0, false), Some(0), 2, 1.0, BTreeMap::from([(2, 2)])), ((20, 1, true), Some(1), 2, 1.0, BTreeMap::from([(3, 2)]))]
        );
    }
}
