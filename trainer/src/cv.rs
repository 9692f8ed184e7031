//! Cross-validation by the published protocol: for each seed and each validation fold k in 0..4,
//! train on the folds other than k and 4, select the epoch by fold-k accuracy, and report the
//! test accuracy on fold 4 at that epoch; then the mean and standard deviation over all runs, and
//! with several seeds a 95 % confidence interval of the mean from the seeds' own means.
//! Runs live in `OUT/seed{S}/fold{K}/` and resume one by one; `jobs` runs train side by side.
//! With more than one PVT³ run, one stopping rule for provisional answers is calibrated on all
//! their validation answers and written into every run ([`crate::stopping`]).

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use indicatif::{MultiProgress, ProgressBar};
use serde::{Deserialize, Serialize};

use crate::data::TEST_FOLD;
use crate::json::{read_json, write_json_atomically};
use crate::provenance::Stopping;
use crate::prune::{prune_and_fine_tune, PruneStage};
use crate::run_dir::{CrossValidation, Run, CV_CURVES, CV_PARTNER_CURVES, CV_SUMMARY};
use crate::train::{train, RunResult, RunSpec};
use crate::{Error, Result};

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CvSummary {
    pub data: String,
    /// The condition's levels held out as every run's test set (`--hold-out`), if any (with the
    /// seed that drew the first seed's folds around them: each seed draws its own).
    #[serde(default)]
    pub held_out: Option<crate::data::HoldOut>,
    pub seeds: Vec<u64>,
    pub runs: Vec<RunResult>,
    pub mean_test_accuracy: f64,
    pub std_test_accuracy: f64,
    pub mean_val_accuracy: f64,
    /// Each seed's mean test accuracy over its folds, in the order of `seeds`.
    #[serde(default)]
    pub seed_means: Vec<f64>,
    /// The 95 % confidence interval of the mean test accuracy: Student's t over `seed_means`
    /// (the folds of one seed share their training data, so they are not independent draws).
    /// `None` with one seed.
    #[serde(default)]
    pub ci95_test_accuracy: Option<[f64; 2]>,
    /// With pruning: the pruned and fine-tuned run of each entry of `runs`.
    #[serde(default)]
    pub pruned_runs: Vec<RunResult>,
    #[serde(default)]
    pub pruned_mean_test_accuracy: Option<f64>,
    /// With pruning: each seed's mean over its pruned runs, and their 95 % interval.
    #[serde(default)]
    pub pruned_seed_means: Vec<f64>,
    #[serde(default)]
    pub pruned_ci95_test_accuracy: Option<[f64; 2]>,
    #[serde(default)]
    pub pruned_std_test_accuracy: Option<f64>,
    #[serde(default)]
    pub pruning: Option<PruneStage>,
    /// Training time summed over runs (they may have run side by side).
    pub train_seconds: f64,
    /// Run directories found still training by `report` (not counted).
    #[serde(default)]
    pub unfinished: Vec<String>,
    /// The stopping rule calibrated on the validation answers of all `runs` (PVT³, more than
    /// one run), as each run's provenance now carries it.
    #[serde(default)]
    pub stopping: Option<Stopping>,
    /// The same for `pruned_runs`.
    #[serde(default)]
    pub pruned_stopping: Option<Stopping>,
    /// A joint run's (`--joint`): the other sensor's networks, summarised alike.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub partner: Option<Box<CvSummary>>,
}

/// Finished runs gathered for a summary: each run, its pruned successor, its directory.
#[derive(Default)]
struct Gathered {
    runs: Vec<RunResult>,
    pruned: Vec<RunResult>,
    dirs: Vec<PathBuf>,
}

impl Gathered {
    fn push(&mut self, fold: FoldResult, dir: PathBuf) {
        self.runs.push(fold.dense);
        self.pruned.extend(fold.pruned);
        self.dirs.push(dir);
    }

    /// The summary of the runs, with their stopping rule calibrated together and their figure
    /// drawn into `out/figure`.
    fn summarize(self, data: String, stage: Option<PruneStage>, out: &Path, figure: &str) -> Result<CvSummary> {
        let seeds: Vec<u64> = self.runs.iter().map(|r| r.seed).collect::<std::collections::BTreeSet<_>>().into_iter().collect();
        let mut summary = summarize(data, &seeds, self.runs, self.pruned, stage);
        calibrate_stopping(&mut summary, &self.dirs)?;
        write_figure(out, &summary, &self.dirs, figure)?;
        Ok(summary)
    }
}

/// One fold's results: the trained run and, with pruning, its pruned and fine-tuned successor;
/// a joint run's other sensor's the same.
struct FoldResult {
    dense: RunResult,
    pruned: Option<RunResult>,
    partner: Option<Box<FoldResult>>,
}

fn run_fold(spec: &RunSpec, stage: Option<&PruneStage>, dir: &Path, resume: bool, bar: &ProgressBar) -> Result<Option<FoldResult>> {
    // Each network of the run (two in a joint run) in its run directory, with its data.
    let partner_dir = Run(dir).partner();
    let partner = spec.partner.as_ref().map(|p| (partner_dir.as_path(), p.data));
    if stage.is_some() {
        // The pruned halves' directories exist from the start, so that `report` sees a run whose
        // dense half has finished as unfinished, not as a run trained without pruning.
        for (net, _) in std::iter::once((dir, spec.data)).chain(partner) {
            let pruned = Run(net).pruned();
            std::fs::create_dir_all(&pruned).map_err(Error::io(&pruned))?;
        }
    }
    let Some(dense) = train(spec, dir, resume, bar)? else {
        return Ok(None);
    };
    // Each network is pruned and fine-tuned alone; `None`: paused.
    let prune = |net: &Path, data| match stage {
        Some(stage) => prune_and_fine_tune(net, data, stage, &Run(net).pruned(), resume, bar).map(|p| p.map(Some)),
        None => Ok(Some(None)),
    };
    let Some(pruned) = prune(dir, spec.data)? else { return Ok(None) };
    let partner = match partner {
        Some((net, data)) => {
            let Some(pruned) = prune(net, data)? else { return Ok(None) };
            Some(Box::new(FoldResult { dense: read_json(&Run(net).result())?, pruned, partner: None }))
        }
        None => None,
    };
    Ok(Some(FoldResult { dense, pruned, partner }))
}

/// Mean and sample standard deviation.
pub fn mean_std(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (mean, var.sqrt())
}

/// The two-sided 95 % quantile of Student's t with `df` degrees of freedom: tabled to 30, then
/// the Cornish–Fisher expansion to its second term (within 0.001 beyond).
pub fn t_975(df: usize) -> f64 {
    const TABLE: [f64; 30] = [
        12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160, 2.145, 2.131, 2.120, 2.110, 2.101,
        2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056, 2.052, 2.048, 2.045, 2.042,
    ];
    let z: f64 = 1.959_964;
    match df {
        0 => f64::INFINITY,
        1..=30 => TABLE[df - 1],
        _ => {
            let n = df as f64;
            z + (z.powi(3) + z) / (4.0 * n) + (5.0 * z.powi(5) + 16.0 * z.powi(3) + 3.0 * z) / (96.0 * n * n)
        }
    }
}

/// Why a cross-validation of one seed gives no interval, and how to get one: `pvt3 cv` says it,
/// and `pvt3 final` records it where the interval would be.
pub const NO_INTERVAL: &str =
    "no 95 % confidence interval: the interval of the mean is over the seeds' means, so it needs two seeds at least (--seeds 0,1,2 runs three, each over the four folds)";

/// The 95 % confidence interval of the mean of `values` (Student's t); `None` for fewer than two.
pub fn ci95(values: &[f64]) -> Option<[f64; 2]> {
    (values.len() >= 2).then(|| {
        let (mean, sd) = mean_std(values);
        let half = t_975(values.len() - 1) * sd / (values.len() as f64).sqrt();
        [mean - half, mean + half]
    })
}

/// Every (seed, validation fold) of the protocol for `seeds`.
pub fn protocol(seeds: &[u64]) -> Vec<(u64, usize)> {
    seeds.iter().flat_map(|&s| (0..TEST_FOLD).map(move |k| (s, k))).collect()
}

/// Refuses `jobs` of 0 (nothing would train) and a run of `work` asked twice (its two would
/// meet in one directory), naming the option.
fn check_work(work: &[(u64, usize)], jobs: usize) -> Result<()> {
    if jobs == 0 {
        return Err(Error::Usage("--jobs 0: expected 1 or more runs side by side".into()));
    }
    match work.iter().enumerate().find_map(|(i, w)| work[..i].contains(w).then_some(*w)) {
        Some((seed, fold)) => Err(Error::Usage(format!("seed {seed}'s fold {fold} is asked twice (--seeds names a seed once)"))),
        None => Ok(()),
    }
}

/// Trains the (seed, validation fold) runs of `work` ([`protocol`], or one run of it) under
/// `out`, `jobs` at a time, each from the spec of its seed in `specs` (`options.seed`: each seed
/// may split the data its own way), and summarises them. `None`: the runs paused (see
/// [`RunSpec::pause_after`]); resume to finish them.
#[allow(clippy::too_many_arguments)]
pub fn cross_validate(
    specs: &[RunSpec],
    stage: Option<&PruneStage>,
    work: &[(u64, usize)],
    out: &Path,
    resume: bool,
    jobs: usize,
    progress: &MultiProgress,
    style: &indicatif::ProgressStyle,
) -> Result<Option<CvSummary>> {
    let spec_of = |seed: u64| {
        specs.iter().find(|s| s.options.seed == seed).ok_or_else(|| Error::Usage(format!("no run specification for seed {seed}")))
    };
    check_work(work, jobs)?;
    let spec = spec_of(work.first().map_or(0, |w| w.0))?;
    for &(seed, _) in work {
        spec_of(seed)?;
    }
    let results = run_jobs(work, jobs, |seed, fold| {
        let bar = progress.add(ProgressBar::new(0).with_style(style.clone()));
        bar.set_prefix(format!("seed {seed} fold {fold}"));
        let run_spec = RunSpec { val_fold: Some(fold), ..spec_of(seed).expect("checked above").clone() };
        let result = run_fold(&run_spec, stage, &CrossValidation(out).run(seed, fold), resume, &bar);
        bar.finish();
        result
    });
    let (mut own, mut partners) = (Gathered::default(), Gathered::default());
    let finished = results.into_iter().zip(work).filter_map(|(r, w)| Some((r?, w)));
    for (r, &(seed, fold)) in finished {
        let Some(mut result) = r? else { return Ok(None) };
        let dir = CrossValidation(out).run(seed, fold);
        if let Some(partner) = result.partner.take() {
            partners.push(*partner, Run(&dir).partner());
        }
        own.push(result, dir);
    }
    let mut summary = own.summarize(spec.data.path.display().to_string(), stage.cloned(), out, CV_CURVES)?;
    summary.held_out = spec.data.held_out.clone();
    if let Some(p) = &spec.partner {
        summary.partner = Some(Box::new(partners.summarize(p.data.path.display().to_string(), stage.cloned(), out, CV_PARTNER_CURVES)?));
    }
    write_json_atomically(&out.join(CV_SUMMARY), &summary)?;
    Ok(Some(summary))
}

/// Runs `run` on each (seed, fold) of `work`, `jobs` at a time, and returns their results in the
/// order of `work`: `None` for a run that never started, because one before it failed (once a run
/// fails, no other starts).
fn run_jobs<T: Send>(work: &[(u64, usize)], jobs: usize, run: impl Fn(u64, usize) -> Result<T> + Sync) -> Vec<Option<Result<T>>> {
    let next = AtomicUsize::new(0);
    let results = Mutex::new(work.iter().map(|_| None).collect::<Vec<_>>());
    std::thread::scope(|scope| {
        for _ in 0..jobs.min(work.len().max(1)) {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::SeqCst);
                let Some(&(seed, fold)) = work.get(i) else {
                    break;
                };
                let result = run(seed, fold);
                let failed = result.is_err();
                results.lock().expect("no panics while holding the lock")[i] = Some(result);
                if failed {
                    next.store(work.len(), Ordering::SeqCst);
                }
            });
        }
    });
    results.into_inner().expect("threads joined")
}

/// The figure of all the runs (`out/figure`), titled with the summary's accuracy.
pub fn write_figure(out: &Path, summary: &CvSummary, dirs: &[PathBuf], figure: &str) -> Result<()> {
    let title = format!(
        "{} runs: test accuracy {:.4} ± {:.4} (mean ± std)",
        summary.runs.len(),
        summary.mean_test_accuracy,
        summary.std_test_accuracy
    );
    crate::plot::curves::write_cv(out, dirs, &title, figure).map(|_| ())
}

/// With more than one run: one stopping rule on all the runs' validation answers, and one on
/// their pruned successors' ([`crate::stopping`]), into the runs and the summary.
fn calibrate_stopping(summary: &mut CvSummary, dirs: &[std::path::PathBuf]) -> Result<()> {
    if dirs.len() < 2 {
        return Ok(());
    }
    summary.stopping = crate::stopping::calibrate_together(dirs)?;
    if !summary.pruned_runs.is_empty() {
        let pruned: Vec<_> = dirs.iter().map(|d| Run(d).pruned()).collect();
        summary.pruned_stopping = crate::stopping::calibrate_together(&pruned)?;
    }
    Ok(())
}

/// The summary of finished runs (each seed's folds, and with pruning their pruned successors).
fn summarize(data: String, seeds: &[u64], runs: Vec<RunResult>, pruned_runs: Vec<RunResult>, stage: Option<PruneStage>) -> CvSummary {
    let pruned_tests: Vec<f64> = pruned_runs.iter().map(|r| r.test_accuracy).collect();
    let pruned_stats = (!pruned_tests.is_empty()).then(|| mean_std(&pruned_tests));
    let tests: Vec<f64> = runs.iter().map(|r| r.test_accuracy).collect();
    let vals: Vec<f64> = runs.iter().map(|r| r.val_accuracy).collect();
    let (mean_test_accuracy, std_test_accuracy) = mean_std(&tests);
    let seed_means = |runs: &[RunResult]| -> Vec<f64> {
        seeds
            .iter()
            .filter_map(|&s| {
                let tests: Vec<f64> = runs.iter().filter(|r| r.seed == s).map(|r| r.test_accuracy).collect();
                (!tests.is_empty()).then(|| mean_std(&tests).0)
            })
            .collect()
    };
    let (pruned_seed_means, seed_means) = (seed_means(&pruned_runs), seed_means(&runs));
    CvSummary {
        pruned_ci95_test_accuracy: ci95(&pruned_seed_means),
        pruned_seed_means,
        ci95_test_accuracy: ci95(&seed_means),
        seed_means,
        data,
        held_out: None,
        seeds: seeds.to_vec(),
        mean_test_accuracy,
        std_test_accuracy,
        mean_val_accuracy: mean_std(&vals).0,
        train_seconds: runs.iter().chain(&pruned_runs).map(|r| r.wall_seconds).sum(),
        runs,
        pruned_mean_test_accuracy: pruned_stats.map(|s| s.0),
        pruned_std_test_accuracy: pruned_stats.map(|s| s.1),
        pruned_runs,
        pruning: stage,
        unfinished: Vec::new(),
        stopping: None,
        pruned_stopping: None,
        partner: None,
    }
}

/// What a run was trained with, besides its seed (and the seed that drew its folds): runs
/// reported together must agree on it.
struct Setup {
    config: pvt3_models::Config,
    data: String,
    held_out: Option<crate::data::HoldOut>,
    options: crate::options::TrainOptions,
    pruning: Option<PruneStage>,
}

impl PartialEq for Setup {
    fn eq(&self, other: &Self) -> bool {
        let same_held_out = match (&self.held_out, &other.held_out) {
            (Some(a), Some(b)) => a.same_touches(b),
            (None, None) => true,
            _ => false,
        };
        (&self.config, &self.data, &self.options, &self.pruning) == (&other.config, &other.data, &other.options, &other.pruning)
            && same_held_out
    }
}

/// Reports every finished run under `out` (`seed{S}/fold{K}/`, as `cross_validate` and separate
/// `--only` jobs write them) into `out/cv.json`, trains nothing and deletes nothing; with more
/// than one finished PVT³ run, their stopping rule is calibrated on all of them and written into
/// each (as `cross_validate` does). Runs still training are listed as unfinished. Refused: no finished run, runs trained differently (data,
/// configuration, options or pruning), a run whose files are damaged or half written.
pub fn report(out: &Path) -> Result<CvSummary> {
    let refuse = |reason: String| Error::Usage(format!("cannot report {}: {reason}", out.display()));
    let (mut own, mut partners, mut unfinished) = (Gathered::default(), Gathered::default(), Vec::new());
    let mut setups: [Option<(Setup, PathBuf)>; 2] = [None, None];
    for (seed, fold, dir) in CrossValidation(out).runs()? {
        // The run's network, and a joint run's other sensor's (finished before it).
        let partner = Run(&dir).partner();
        let nets = [Some(dir.clone()), Some(partner).filter(|p| p.is_dir())];
        let mut found = Vec::new();
        for (net, setup) in nets.iter().zip(&mut setups) {
            let Some(net) = net else { continue };
            let Some((fold_result, this)) = finished_run(net, &mut unfinished).map_err(|e| refuse(e.to_string()))? else {
                break;
            };
            check_alike(net, (seed, fold), &fold_result, this, setup).map_err(refuse)?;
            found.push((fold_result, net.clone()));
        }
        if found.len() < nets.iter().flatten().count() {
            continue;
        }
        let mut found = found.into_iter();
        let (fold_result, net) = found.next().expect("the run's own network");
        own.push(fold_result, net);
        if let Some((fold_result, net)) = found.next() {
            partners.push(fold_result, net);
        }
    }
    let [Some((setup, _)), partner_setup] = setups else {
        return Err(refuse(format!("no finished run under it (seed*/fold*/result.json; {} unfinished)", unfinished.len())));
    };
    let mut summary = own.summarize(setup.data, setup.pruning, out, CV_CURVES)?;
    summary.held_out = setup.held_out;
    if let Some((partner, _)) = partner_setup {
        summary.partner = Some(Box::new(partners.summarize(partner.data, partner.pruning, out, CV_PARTNER_CURVES)?));
    }
    summary.unfinished = unfinished;
    write_json_atomically(&out.join(CV_SUMMARY), &summary)?;
    Ok(summary)
}

/// Refuses the finished run in `net` where it is not the run of `seed` and `fold` that its
/// directory names, or was trained otherwise (`this`) than the first run read (`setup`, which it
/// becomes where none was read before).
fn check_alike(
    net: &Path,
    (seed, fold): (u64, usize),
    result: &FoldResult,
    this: Setup,
    setup: &mut Option<(Setup, PathBuf)>,
) -> std::result::Result<(), String> {
    if (result.dense.seed, result.dense.val_fold) != (seed, Some(fold)) {
        let trained = result.dense.val_fold.map_or("trained on every touch".into(), |k| format!("fold {k}"));
        return Err(format!("{} holds the run of seed {} {trained}", net.display(), result.dense.seed));
    }
    match setup {
        None => *setup = Some((this, net.to_path_buf())),
        Some((first, first_dir)) if *first != this => {
            return Err(format!(
                "{} and {} were trained differently (data, held-out levels, configuration, options or pruning)",
                first_dir.display(),
                net.display()
            ));
        }
        Some(_) => {}
    }
    Ok(())
}

/// The finished run in `dir` (with its pruned successor, when it has one) and how it was trained;
/// `None`, and `dir` or its pruned half added to `unfinished`, while it trains.
fn finished_run(dir: &Path, unfinished: &mut Vec<String>) -> Result<Option<(FoldResult, Setup)>> {
    let damaged = |e: Error| Error::Usage(format!("{} is damaged or half written ({e})", dir.display()));
    if !Run(dir).result().exists() {
        unfinished.push(dir.display().to_string());
        return Ok(None);
    }
    let run: RunResult = read_json(&Run(dir).result()).map_err(damaged)?;
    let (_, meta) = crate::checkpoint::load_meta(&Run(dir).model()).map_err(damaged)?;
    let pruned = Run(dir).pruned();
    let (pruned_run, pruning) = match Run(&pruned).result().exists() {
        true => {
            let (_, pmeta) = crate::checkpoint::load_meta(&pruned).map_err(damaged)?;
            let o = &pmeta.provenance.options;
            let stage = pmeta.provenance.pruning.map(|spec| PruneStage {
                spec,
                epochs: o.optimization.epochs,
                lr: o.optimization.lr,
                kept_patches: None,
            });
            (Some(read_json::<RunResult>(&Run(&pruned).result()).map_err(damaged)?), stage)
        }
        false if pruned.exists() => {
            unfinished.push(pruned.display().to_string());
            return Ok(None);
        }
        false => (None, None),
    };
    let options = crate::options::TrainOptions { seed: 0, ..meta.provenance.options };
    let setup = Setup { config: meta.config, data: meta.provenance.data, held_out: meta.provenance.held_out, options, pruning };
    Ok(Some((FoldResult { dense: run, pruned: pruned_run, partner: None }, setup)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::train::tests::{out_dir, spec, tiny_data};

    /// No job count of 0 (nothing would train), and no seed asked twice (its runs would meet in
    /// one directory): refused before anything trains, naming the option.
    #[test]
    fn no_jobs_and_a_seed_twice_are_refused() {
        let (data, out) = (tiny_data(), out_dir("cv-refused"));
        let specs = [spec(&data, 1, None)];
        let seed = specs[0].options.seed;
        let cv = |work: &[(u64, usize)], jobs| {
            let hidden = MultiProgress::with_draw_target(indicatif::ProgressDrawTarget::hidden());
            cross_validate(&specs, None, work, &out, false, jobs, &hidden, &indicatif::ProgressStyle::default_bar())
                .unwrap_err()
                .to_string()
        };
        assert!(cv(&protocol(&[seed]), 0).contains("--jobs 0: expected 1 or more"));
        assert!(cv(&protocol(&[seed, seed]), 2).contains(&format!("seed {seed}'s fold 0 is asked twice")));
        assert!(!out.exists() || std::fs::read_dir(&out).unwrap().next().is_none(), "nothing trained");
    }

    /// A pruning run's `pruned/` exists while its dense half trains, so a report in that window
    /// lists the run as unfinished rather than as trained without pruning.
    #[test]
    fn a_pruning_run_is_unfinished_until_its_pruned_half_is_done() {
        let (data, out) = (tiny_data(), out_dir("cv-window"));
        let dir = out.join("seed5/fold0");
        let spec = spec(&data, 2, Some(1));
        let stage = PruneStage {
            spec: pvt3_spec::prune::PruneSpec {
                channels: 0.0,
                frames: 0.0,
                patches: 0.0,
                scope: Default::default(),
                weights: 20.0,
                patch_choice: Default::default(),
            },
            epochs: 1,
            lr: 1e-3,
            kept_patches: None,
        };
        assert!(run_fold(&spec, Some(&stage), &dir, false, &ProgressBar::hidden()).unwrap().is_none(), "paused");
        assert!(Run(&dir).pruned().is_dir());
        // The dense half finished (as a job in the window would leave it): still unfinished.
        let finished = RunSpec { pause_after: None, ..spec };
        train(&finished, &dir, true, &ProgressBar::hidden()).unwrap().unwrap();
        let err = report(&out).unwrap_err().to_string();
        assert!(err.contains("no finished run under it") && err.contains("1 unfinished"), "{err}");
        std::fs::remove_dir_all(out).unwrap();
    }

    /// Pruned runs get their own seed means and interval, as the dense ones.
    #[test]
    fn pruned_runs_are_summarised_per_seed_as_the_dense_ones() {
        let run = |seed, val_fold, test_accuracy| RunResult {
            val_fold: Some(val_fold),
            seed,
            best_epoch: 1,
            val_accuracy: 0.9,
            test_accuracy,
            epochs: 1,
            wall_seconds: 1.0,
            head: None,
        };
        let dense = vec![run(0, 0, 0.9), run(0, 1, 1.0), run(1, 0, 0.8), run(1, 1, 0.9)];
        let pruned = vec![run(0, 0, 0.8), run(0, 1, 0.8), run(1, 0, 0.7), run(1, 1, 0.7)];
        let s = summarize("d".into(), &[0, 1], dense, pruned, None);
        assert_eq!((s.seed_means.len(), s.pruned_seed_means.len()), (2, 2));
        assert!((s.seed_means[0] - 0.95).abs() < 1e-12 && (s.pruned_seed_means[1] - 0.7).abs() < 1e-12);
        assert_eq!(s.pruned_ci95_test_accuracy, ci95(&[0.8, 0.7]));
        assert!(s.pruned_ci95_test_accuracy.is_some() && s.ci95_test_accuracy != s.pruned_ci95_test_accuracy);
        let unpruned = summarize("d".into(), &[0], vec![run(0, 0, 0.9)], Vec::new(), None);
        assert!(unpruned.pruned_seed_means.is_empty() && unpruned.pruned_ci95_test_accuracy.is_none());
    }

    #[test]
    fn mean_std_is_the_sample_statistic() {
        let (m, s) = super::mean_std(&[0.9, 0.95, 1.0]);
        assert!((m - 0.95).abs() < 1e-12 && (s - 0.05).abs() < 1e-12);
        assert_eq!(super::mean_std(&[0.5]), (0.5, 0.0));
    }

    #[test]
    fn the_interval_is_students_over_the_seed_means() {
        // Three seeds' means 0.90, 0.95, 1.00: mean 0.95, sd 0.05, t(2) = 4.303.
        let [lo, hi] = super::ci95(&[0.9, 0.95, 1.0]).unwrap();
        let half = 4.303 * 0.05 / 3f64.sqrt();
        assert!((lo - (0.95 - half)).abs() < 1e-12 && (hi - (0.95 + half)).abs() < 1e-12);
        assert_eq!(super::ci95(&[0.9]), None);
        // The expansion joins the table smoothly and tends to the normal quantile.
        assert!((super::t_975(31) - 2.0395).abs() < 0.001 && (super::t_975(120) - 1.9799).abs() < 0.001);
        assert!(super::t_975(100_000) > 1.959 && super::t_975(100_000) < 1.961);
    }
}
