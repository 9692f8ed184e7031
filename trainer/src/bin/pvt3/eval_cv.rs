//! `pvt3 eval CV_DIR`: every finished run of a cross-validation on one fold (by default the test
//! fold), their answers together: the runs' accuracy as mean ± std and the confusion matrix of
//! all their answers, or with `--anytime` what the stopping rule `pvt3 cv` wrote into the runs
//! does, run by run (mean ± std, the figures docs/anytime.md gives) and pooled (drawn).
//! `--pruned` reads each run's pruned model instead.

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};
use pvt3_trainer::anytime::{self, Prefixes};
use pvt3_trainer::cv::mean_std;
use pvt3_trainer::evaluate::evaluate;
use pvt3_trainer::run_dir::{CrossValidation, Run, CV_SUMMARY};

use crate::eval::{describe, draw_anytime, print_tenths, report_classes, tenths, EvalArgs, Loaded};

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
    for dir in &runs {
        let run = load(dir, a, &mut classes)?;
        let e = evaluate(&run.model, &run.samples())?;
        accuracies.push(e.accuracy);
        labels.extend(e.labels);
        predictions.extend(e.predictions);
    }
    let (dir, fold, n) = (a.checkpoint.display(), a.fold, runs.len());
    let (mean, std) = mean_std(&accuracies);
    println!("{n} {what} of {dir}, fold {fold}: accuracy {mean:.4} ± {std:.4} (mean ± std over the runs)");
    println!("their {} answers together:", labels.len());
    let right = labels.iter().zip(&predictions).filter(|(l, p)| l == p).count() as f64 / labels.len() as f64;
    let title = format!("{dir}: {n} {what}, fold {fold}, {} answers, accuracy {right:.4}", labels.len());
    let name = if a.pruned { "confusion-pruned" } else { "confusion" };
    report_classes(&classes, &labels, &predictions, &title, &a.picture_of(name))
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

/// The checkpoints to read: each finished run of the cross-validation, or its pruned successor.
fn finished(a: &EvalArgs) -> Result<Vec<PathBuf>> {
    let mut found = Vec::new();
    for (_, _, dir) in CrossValidation(&a.checkpoint).runs()? {
        let net = if a.pruned { Run(&dir).pruned() } else { dir };
        if Run(&net).result().exists() {
            found.push(net);
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
    let mut rule = None;
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
        let prefixes = anytime::prefixes(run.model.pvt3("pvt3 eval --anytime")?, &run.samples())?;
        let here = prefixes.stop_by(stopping.rule);
        changes.push(100.0 * (here.accuracy - here.full_accuracy));
        shares.push(100.0 * here.mean_share);
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
    print_tenths(&tenths(&pooled));
    println!("stopping rule: {}", describe(&calibrated));
    let ((change, change_std), (share, share_std)) = (mean_std(&changes), mean_std(&shares));
    println!("here, run by run: {change:+.1} ± {change_std:.1} points against the whole touch, at {share:.0} ± {share_std:.0} % of the touch (mean ± std over the runs)");
    let title = format!(
        "{dir}: {n} {what}, fold {fold}; rule: top probability ≥ {:.4}, {} agreeing",
        calibrated.rule.top_probability, calibrated.rule.agreeing
    );
    let picture = a.picture_of(if a.pruned { "anytime-pruned" } else { "anytime" });
    draw_anytime(&picture, &title, &pooled, calibrated.rule)?;
    println!("drew {}", picture.display());
    Ok(())
}
