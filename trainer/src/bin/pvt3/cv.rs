//! `pvt3 cv`: the published protocol over seeds × folds, side by side or one run per job, and a
//! report of whatever has finished.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Result;
use indicatif::MultiProgress;
use pvt3_trainer::cv::{self, cross_validate, CvSummary};
use pvt3_trainer::data::TEST_FOLD;
use pvt3_trainer::run_dir;

use crate::model_args::{prepare_seeds, ModelArgs};
use crate::progress;
use crate::prune_args::PruneArgs;

/// The published protocol: 4-fold cross-validation, test on fold 4, mean ± std over seeds.
#[derive(clap::Args)]
pub struct CvArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// Seeds to repeat the four folds with, comma-separated. Each seed initialises its own
    /// networks and, on a set without a fold array (or with --hold-out), draws its own folds.
    #[arg(long, value_delimiter = ',', default_value = "0")]
    pub seeds: Vec<u64>,
    /// The cross-validation's directory: a run directory per seed and fold (OUT/seed0/fold0, …),
    /// cv.json (the summary and the stopping rule) and cv-curves.svg.
    #[arg(long, short, default_value = "runs/cv")]
    pub out: PathBuf,
    /// Continue: finished folds are kept, an interrupted one resumes.
    #[arg(long)]
    pub resume: bool,
    /// Folds trained side by side (each on one thread).
    #[arg(long, default_value_t = 1)]
    pub jobs: usize,
    /// With --prune-channels/--prune-frames: every fold is also pruned and fine-tuned
    /// (OUT/seed*/fold*/pruned), and both results are reported.
    #[command(flatten)]
    pub prune: PruneArgs,
    /// Train this one run alone, `seed=S,fold=K` (one job of a job array, e.g.
    /// bench/slurm/cv.sbatch, writing into the shared OUT), then report every finished run
    /// there. Instead of --seeds.
    #[arg(long, value_parser = parse_only, conflicts_with = "seeds")]
    pub only: Option<(u64, usize)>,
    /// Train nothing: report the finished runs under this directory (cv.json and the table),
    /// whoever trained them. Runs still training are listed, not counted.
    #[arg(long, value_name = "OUT", conflicts_with_all = ["only", "resume"])]
    pub report: Option<PathBuf>,
    /// Print the summary (what cv.json holds) as one JSON object on standard output instead of
    /// the table.
    #[arg(long)]
    pub json: bool,
}

pub fn run(a: CvArgs) -> Result<()> {
    let started = Instant::now();
    let (s, out) = match a.report {
        Some(dir) => (cv::report(&dir)?, dir),
        None => {
            let seeds = a.only.map_or_else(|| a.seeds.clone(), |(seed, _)| vec![seed]);
            let prepared = prepare_seeds(&a.model, &seeds)?;
            let stage = a.prune.stage();
            if stage.is_some() {
                prepared.iter().try_for_each(|p| p.config.require_pvt3("pruning"))?;
            }
            let multi = MultiProgress::new();
            let specs: Vec<_> = prepared.iter().map(|p| p.spec(&a.model, 0)).collect();
            let s = match a.only {
                Some(one) => match cross_validate(&specs, stage.as_ref(), &[one], &a.out, a.resume, 1, &multi, &progress::style())? {
                    Some(_) => Some(cv::report(&a.out)?),
                    None => None,
                },
                None => {
                    cross_validate(&specs, stage.as_ref(), &cv::protocol(&a.seeds), &a.out, a.resume, a.jobs, &multi, &progress::style())?
                }
            };
            let Some(s) = s else {
                match a.json {
                    true => println!("{}", serde_json::json!({"paused": true})),
                    false => println!("paused; continue with the same command and --resume"),
                }
                return Ok(());
            };
            (s, a.out)
        }
    };
    if a.json {
        println!("{}", serde_json::to_string(&s)?);
        return Ok(());
    }
    print_summary(&s, started.elapsed().as_secs_f64(), &out.join(run_dir::CV_SUMMARY));
    print_next(&s, &out);
    Ok(())
}

/// What to do with the runs: look at all their answers, train the model to ship.
fn print_next(s: &CvSummary, out: &Path) {
    if s.runs.is_empty() {
        return;
    }
    let pruned = if s.pruned_runs.is_empty() { "" } else { " --pruned" };
    println!(
        "next: pvt3 eval {0}{pruned} (all runs' test answers together, confusion matrix drawn; --anytime: the stopping rule run by run), pvt3 final {0} -o model.onnx (the file for the robot, trained on every touch as these runs chose)",
        out.display(),
    );
}

fn print_summary(s: &CvSummary, wall: f64, summary: &std::path::Path) {
    print_runs(s, wall, summary);
    if let Some(partner) = &s.partner {
        println!(
            "\nthe other sensor's networks, trained beside on {} and each tested on it alone (OUT/seed*/fold*/partner):",
            partner.data
        );
        print_runs(partner, wall, summary);
    }
}

fn print_runs(s: &CvSummary, wall: f64, summary: &std::path::Path) {
    for dir in &s.unfinished {
        println!("not finished, not counted: {dir}");
    }
    print_table(s);
    print_accuracy(s, wall, summary);
}

/// A line a run: its seed, fold, chosen epoch, validation and test accuracy, seconds, pruned
/// successor's test accuracy and, for a camera head, its form.
fn print_table(s: &CvSummary) {
    // A camera head's form, as each run's validation fold chose it (docs/camera.md).
    let heads = s.runs.iter().any(|r| r.head.is_some());
    let head = |r: &pvt3_trainer::train::RunResult| match (heads, r.head) {
        (false, _) => String::new(),
        (true, form) => format!(" {:>8}", form.map_or("-".into(), |f| f.to_string())),
    };
    let head_title = if heads { format!(" {:>8}", "head") } else { String::new() };
    println!("{:>6} {:>5} {:>6} {:>8} {:>8} {:>8} {:>12}{head_title}", "seed", "fold", "epoch", "val", "test", "seconds", "pruned test");
    for (i, r) in s.runs.iter().enumerate() {
        let pruned = s.pruned_runs.get(i).map_or(String::new(), |p| format!("{:.4}", p.test_accuracy));
        println!(
            "{:>6} {:>5} {:>6} {:>8.4} {:>8.4} {:>8.0} {:>12}{}",
            r.seed,
            r.val_fold.map_or("-".into(), |k| k.to_string()),
            r.best_epoch,
            r.val_accuracy,
            r.test_accuracy,
            r.wall_seconds,
            pruned,
            head(r)
        );
    }
}

/// The runs' accuracy (pruned and not) with its interval, and their stopping rules.
fn print_accuracy(s: &CvSummary, wall: f64, summary: &std::path::Path) {
    if let (Some(m), Some(sd)) = (s.pruned_mean_test_accuracy, s.pruned_std_test_accuracy) {
        let interval =
            s.pruned_ci95_test_accuracy.map_or(String::new(), |[lo, hi]| format!(", 95 % confidence interval [{lo:.4}, {hi:.4}]"));
        println!("pruned and fine-tuned: mean test accuracy {m:.4} ± {sd:.4} over {} runs{interval}", s.pruned_runs.len());
    }
    if let Some(h) = &s.held_out {
        println!("the test set of every run: the touches of {h}, held out of training and validation");
    }
    println!(
        "mean test accuracy {:.4} ± {:.4} over {} runs (wall {wall:.0} s); summary {}",
        s.mean_test_accuracy,
        s.std_test_accuracy,
        s.runs.len(),
        summary.display()
    );
    match s.ci95_test_accuracy {
        Some([lo, hi]) => {
            let means: Vec<String> = s.seed_means.iter().map(|m| format!("{m:.4}")).collect();
            println!("95 % confidence interval of the mean [{lo:.4}, {hi:.4}] (Student's t over the seeds' means {})", means.join(", "));
        }
        None => println!("{}", cv::NO_INTERVAL),
    }
    for (runs, stopping) in [("runs", &s.stopping), ("pruned runs", &s.pruned_stopping)] {
        if let Some(st) = stopping {
            println!(
                "stopping rule, written into every one of the {runs}: {}; on their validation answers accuracy {:.4} against {:.4} for the whole touch, {:.0} % of the touch used",
                st.rule,
                st.accuracy,
                st.full_accuracy,
                st.mean_share * 100.0
            );
        }
    }
}

/// `--only seed=S,fold=K`.
fn parse_only(text: &str) -> std::result::Result<(u64, usize), String> {
    let mut seed_fold = (None, None);
    for part in text.split(',') {
        match part.trim().split_once('=') {
            Some(("seed", v)) => seed_fold.0 = v.parse::<u64>().ok(),
            Some(("fold", v)) => seed_fold.1 = v.parse::<usize>().ok().filter(|k| *k < TEST_FOLD),
            _ => return Err(format!("`{part}`: expected seed=S,fold=K")),
        }
    }
    match seed_fold {
        (Some(s), Some(k)) => Ok((s, k)),
        _ => Err(format!("`{text}`: expected seed=S,fold=K with a validation fold from 0 to {}", TEST_FOLD - 1)),
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn only_takes_one_seed_and_a_validation_fold() {
        assert_eq!(super::parse_only("seed=2,fold=3"), Ok((2, 3)));
        assert_eq!(super::parse_only(" fold=0 , seed=7"), Ok((7, 0)));
        for bad in ["seed=2", "seed=2,fold=4", "seed=-1,fold=0", "seed=1;fold=0", "fold=1,seed=x"] {
            assert!(super::parse_only(bad).is_err(), "{bad}");
        }
    }
}
