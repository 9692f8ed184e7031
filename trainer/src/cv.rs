//! Cross-validation by the published protocol: for each seed and each validation fold k in 0..4,
//! train on the folds other than k and 4, select the epoch by fold-k accuracy, and report the
//! test accuracy on fold 4 at that epoch; then the mean and standard deviation over all runs.
//! Runs live in `OUT/seed{S}/fold{K}/` and resume one by one; `jobs` runs train side by side.

use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use indicatif::{MultiProgress, ProgressBar};
use serde::{Deserialize, Serialize};

use crate::checkpoint::write_json;
use crate::data::TEST_FOLD;
use crate::prune::{prune_and_fine_tune, PruneStage};
use crate::train::{train, RunResult, RunSpec};
use crate::Result;

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CvSummary {
    pub data: String,
    pub seeds: Vec<u64>,
    pub runs: Vec<RunResult>,
    pub mean_test_accuracy: f64,
    pub std_test_accuracy: f64,
    pub mean_val_accuracy: f64,
    /// With pruning: the pruned and fine-tuned run of each entry of `runs`.
    #[serde(default)]
    pub pruned_runs: Vec<RunResult>,
    #[serde(default)]
    pub pruned_mean_test_accuracy: Option<f64>,
    #[serde(default)]
    pub pruned_std_test_accuracy: Option<f64>,
    #[serde(default)]
    pub pruning: Option<PruneStage>,
    /// Training time summed over runs (they may have run side by side).
    pub train_seconds: f64,
}

/// One fold's results: the trained run and, with pruning, its pruned and fine-tuned successor.
struct FoldResult {
    dense: RunResult,
    pruned: Option<RunResult>,
}

fn run_fold(spec: &RunSpec, stage: Option<&PruneStage>, dir: &Path, resume: bool, bar: &ProgressBar) -> Result<Option<FoldResult>> {
    let Some(dense) = train(spec, dir, resume, bar)? else {
        return Ok(None);
    };
    let pruned = match stage {
        Some(stage) => match prune_and_fine_tune(dir, spec.data, stage, &dir.join("pruned"), resume, bar)? {
            Some(p) => Some(p),
            None => return Ok(None),
        },
        None => None,
    };
    Ok(Some(FoldResult { dense, pruned }))
}

/// Mean and sample standard deviation.
pub fn mean_std(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (mean, var.sqrt())
}

/// Runs every (seed, fold) of the protocol under `out`, `jobs` at a time. `None`: the runs
/// paused (see [`RunSpec::pause_after`]); resume to finish them.
#[allow(clippy::too_many_arguments)]
pub fn cross_validate(
    spec: &RunSpec,
    stage: Option<&PruneStage>,
    seeds: &[u64],
    out: &Path,
    resume: bool,
    jobs: usize,
    progress: &MultiProgress,
    style: &indicatif::ProgressStyle,
) -> Result<Option<CvSummary>> {
    let work: Vec<(u64, usize)> = seeds.iter().flat_map(|&s| (0..TEST_FOLD).map(move |k| (s, k))).collect();
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<Result<Option<FoldResult>>>>> = Mutex::new(work.iter().map(|_| None).collect());
    std::thread::scope(|scope| {
        for _ in 0..jobs.clamp(1, work.len().max(1)) {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::SeqCst);
                let Some(&(seed, fold)) = work.get(i) else {
                    break;
                };
                let bar = progress.add(ProgressBar::new(0).with_style(style.clone()));
                bar.set_prefix(format!("seed {seed} fold {fold}"));
                let run_spec =
                    RunSpec { val_fold: fold, options: crate::train::TrainOptions { seed, ..spec.options.clone() }, ..spec.clone() };
                let dir = out.join(format!("seed{seed}")).join(format!("fold{fold}"));
                let result = run_fold(&run_spec, stage, &dir, resume, &bar);
                bar.finish();
                let failed = result.is_err();
                results.lock().expect("no panics while holding the lock")[i] = Some(result);
                if failed {
                    next.store(work.len(), Ordering::SeqCst);
                }
            });
        }
    });
    let (mut runs, mut pruned_runs) = (Vec::new(), Vec::new());
    for r in results.into_inner().expect("threads joined").into_iter().flatten() {
        match r? {
            Some(fold) => {
                runs.push(fold.dense);
                pruned_runs.extend(fold.pruned);
            }
            None => return Ok(None),
        }
    }
    let pruned_tests: Vec<f64> = pruned_runs.iter().map(|r| r.test_accuracy).collect();
    let pruned_stats = (!pruned_tests.is_empty()).then(|| mean_std(&pruned_tests));
    let tests: Vec<f64> = runs.iter().map(|r| r.test_accuracy).collect();
    let vals: Vec<f64> = runs.iter().map(|r| r.val_accuracy).collect();
    let (mean_test_accuracy, std_test_accuracy) = mean_std(&tests);
    let summary = CvSummary {
        data: spec.data.path.display().to_string(),
        seeds: seeds.to_vec(),
        mean_test_accuracy,
        std_test_accuracy,
        mean_val_accuracy: mean_std(&vals).0,
        train_seconds: runs.iter().chain(&pruned_runs).map(|r| r.wall_seconds).sum(),
        runs,
        pruned_mean_test_accuracy: pruned_stats.map(|s| s.0),
        pruned_std_test_accuracy: pruned_stats.map(|s| s.1),
        pruned_runs,
        pruning: stage.cloned(),
    };
    write_json(&out.join("cv.json"), &summary)?;
    Ok(Some(summary))
}

#[cfg(test)]
mod tests {
    #[test]
    fn mean_std_is_the_sample_statistic() {
        let (m, s) = super::mean_std(&[0.9, 0.95, 1.0]);
        assert!((m - 0.95).abs() < 1e-12 && (s - 0.05).abs() < 1e-12);
        assert_eq!(super::mean_std(&[0.5]), (0.5, 0.0));
    }
}
