//! The training loop: epochs of optimiser steps (`epoch`: a sensor's windows, augmented, batched
//! and stepped by its [`Learner`]) with warm-up and cosine decay ([`Schedule`]), weight
//! averaging ([`crate::average`]), epoch selection by validation accuracy, and a stop once it has
//! not risen for `--patience` epochs. Every epoch appends
//! a line to `metrics.jsonl` and saves the run state under `last/`, so `--resume` continues an
//! interrupted run exactly; the best epoch's checkpoint is kept under `model/`. A joint run
//! (`--joint`) is the same loop over two sensors ([`sensor::Sensor`]), which step together.
//!
//! Run directory: `model/` (the checkpoint), `last/` (resume state), `metrics.jsonl`,
//! `result.json` (written when the run is complete); a joint run's other sensor has its own in
//! `partner/`.

use std::fs::File;
use std::io::Write;
use std::path::Path;
use std::time::Instant;

use indicatif::ProgressBar;
use pvt3_models::Config;
use pvt3_spec::prune::PruneSpec;
use pvt3_spec::weights::Tensors;
use serde::{Deserialize, Serialize};

use crate::checkpoint::{self, write_json, write_json_atomically};
use crate::data::windows::Samples;
use crate::data::Dataset;
use crate::joint::Partner;
use crate::options::TrainOptions;
use crate::provenance::nan_from_null;
use crate::run_dir::{Checkpoint, Run};
use crate::schedule::Schedule;
use crate::{Error, Result};
pub use learner::Learner;
use run_state::{Found, RunState};
use sensor::Sensor;
/// The outcome of a finished run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunResult {
    /// `None`: a final model, which every touch trained.
    pub val_fold: Option<usize>,
    pub seed: u64,
    pub best_epoch: usize,
    /// NaN (`null`) where nothing validated or tested.
    #[serde(deserialize_with = "nan_from_null")]
    pub val_accuracy: f64,
    #[serde(deserialize_with = "nan_from_null")]
    pub test_accuracy: f64,
    /// The epochs trained: the options' `epochs`, or fewer where `patience` stopped the run.
    pub epochs: usize,
    pub wall_seconds: f64,
    /// What a camera head read, as its fit chose (`Run::head`); `None` without one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub head: Option<crate::spectrum_fit::form::Form>,
}

/// Everything a run needs besides its output directory.
#[derive(Clone)]
pub struct RunSpec<'a> {
    pub data: &'a Dataset,
    pub config: Config,
    /// The fold that validates (chooses the epoch); `None`: a final model, which every touch
    /// trains and whose last epoch is kept ([`crate::final_model`]).
    pub val_fold: Option<usize>,
    pub options: TrainOptions,
    pub classes: Vec<String>,
    /// Stop after this many epochs in this call, leaving the run to be resumed.
    pub pause_after: Option<usize>,
    /// Weights to start from instead of a seeded initialisation (fine-tuning).
    pub start: Option<Tensors>,
    /// The pruning that produced `start`, recorded in the provenance.
    pub pruning: Option<PruneSpec>,
    /// Joint learning (`--joint`): the second sensor trained beside.
    pub partner: Option<Partner<'a>>,
}

/// Trains one split into `out`; with `resume`, continues the run found there. `None` means the
/// run paused (see [`RunSpec::pause_after`]) and can be resumed. With a partner (`--joint`), its
/// network trains beside, into the run directory `out/partner/` (its resume state inside
/// `out/last/`, so that the two resume together).
pub fn train(spec: &RunSpec, out: &Path, resume: bool, bar: &ProgressBar) -> Result<Option<RunResult>> {
    let (config, opts, last) = match run_state::find(spec, out, resume)? {
        Found::Finished(result) => return Ok(Some(result)),
        Found::Run { config, opts, last } => (config, opts, last),
    };
    // A run from given weights (fine-tuning) keeps its spectral heads as they are, unless it
    // prunes patches a head over the image's space read: it now reads them as 0.
    let prunes_pixels = spec.config.spectral_space() && spec.pruning.as_ref().is_some_and(|p| p.patches > 0.0);
    let fit_heads = last.is_none() && (spec.start.is_none() || prunes_pixels);
    let mut sensors = sensor::of_run(spec, config, &opts, out)?;
    let mut run = run_state::begin(&mut sensors, &opts, last)?;
    for sensor in &mut sensors {
        if let Some(chosen) = sensor.ready(fit_heads, &opts)? {
            bar.println(format!("{}: {chosen}", sensor.dir.display()));
        }
    }
    let steps_per_epoch = sensors[0].split.train.len().div_ceil(opts.optimization.batch_size);
    let schedule = Schedule::new(&opts.optimization, steps_per_epoch);
    bar.set_length((opts.optimization.epochs * steps_per_epoch) as u64);
    bar.set_position((run.epochs_done * steps_per_epoch) as u64);
    let mut logs = sensors.iter().map(|s| open_log(&Run(&s.dir).metrics())).collect::<Result<Vec<_>>>()?;
    let first_epoch = run.epochs_done + 1;
    for epoch in first_epoch..=opts.optimization.epochs {
        if run.stalled(sensors.len(), opts.optimization.patience) {
            break;
        }
        if spec.pause_after.is_some_and(|p| epoch - first_epoch >= p) {
            return Ok(None);
        }
        let started = Instant::now();
        let trained = epoch::train(&mut sensors, epoch, &schedule, &opts, &mut run, bar)?;
        crate::crash::point("stepped");
        // With weight averaging, the average is what is evaluated, selected and checkpointed.
        let validated = (sensors.iter_mut().enumerate())
            .map(|(i, s)| s.validate(epoch, run.best_of(i), (spec.val_fold, &spec.pruning)))
            .collect::<Result<Vec<_>>>()?;
        crate::crash::point("validated");
        let seconds = started.elapsed().as_secs_f64();
        run.wall_seconds += seconds;
        run.epochs_done = epoch;
        // The epoch's metrics line before its resume state: a run killed between the two resumes
        // from the epoch before, whose log it cuts back to (a line after a saved state would be
        // lost).
        for (i, ((sensor, log), (tally, val))) in sensors.iter().zip(&mut logs).zip(trained.tallies.iter().zip(&validated)).enumerate() {
            let line = trained.line(epoch, seconds, tally, val);
            writeln!(log, "{}", serde_json::to_string(&line).expect("plain data")).map_err(Error::io(&sensor.dir))?;
            crate::plot::curves::write_run(&sensor.dir, run.best_of(i).as_ref().map(|b| b.epoch))?;
        }
        crate::crash::point("logged");
        run_state::save_last(&sensors, &Run(out).last(), &run, (spec.val_fold, &spec.pruning), (epoch, &validated))?;
        crate::crash::point("saved");
        let (tally, best) = (&trained.tallies[0], run.best.as_ref().expect("set after the first epoch"));
        bar.set_message(format!(
            "epoch {epoch}/{} loss {:.3} train {:.3} val {:.3} (best {:.3} @ {})",
            opts.optimization.epochs,
            tally.loss / trained.windows,
            tally.correct as f64 / trained.windows,
            validated[0].accuracy,
            best.val_accuracy,
            best.epoch
        ));
    }
    finish(&sensors, spec, &opts, &mut run).map(Some)
}

/// The finished run's results, a joint run's other sensor's first (a run with its `result.json`
/// is a finished joint run), each model's stopping rule calibrated on its validation windows.
fn finish(sensors: &[Sensor], spec: &RunSpec, opts: &TrainOptions, run: &mut RunState) -> Result<RunResult> {
    let mut result = None;
    for (i, sensor) in sensors.iter().enumerate().rev() {
        let best = run.best_of(i).clone().ok_or_else(|| Error::Usage("no epoch was trained (epochs = 0)".into()))?;
        let done = RunResult {
            val_fold: spec.val_fold,
            seed: opts.seed,
            best_epoch: best.epoch,
            val_accuracy: best.val_accuracy,
            test_accuracy: best.test_accuracy,
            epochs: run.epochs_done,
            wall_seconds: run.wall_seconds,
            head: crate::spectrum_fit::recorded(&sensor.dir)?.map(|c| c.choice.form),
        };
        calibrate_stopping(&Run(&sensor.dir).model(), &sensor.val_set)?;
        write_json(&Run(&sensor.dir).result(), &done)?;
        result = Some(done);
    }
    Ok(result.expect("a run has its own sensor"))
}

fn open_log(path: &Path) -> Result<File> {
    std::fs::OpenOptions::new().create(true).append(true).open(path).map_err(Error::io(path))
}

/// Calibrates the stopping rule of provisional answers ([`crate::anytime`]) for the PVT³
/// checkpoint in `dir` on the validation samples, into its provenance (which the exporter
/// writes into the file). Other networks give no provisional answers, and a run with nothing to
/// validate is calibrated by no one here.
fn calibrate_stopping(dir: &Path, val_set: &Samples) -> Result<()> {
    if val_set.is_empty() {
        // A final model takes its cross-validation's rule (`crate::final_model`).
        return Ok(());
    }
    let (mut meta, model, _) = checkpoint::load(dir)?;
    let Some(pvt3) = crate::anytime::answering(&model) else { return Ok(()) };
    meta.provenance.stopping = Some(crate::anytime::prefixes(pvt3, val_set)?.calibrate());
    write_json_atomically(&Checkpoint(dir).provenance(), &meta.provenance)
}

mod epoch;
mod learner;
pub mod loss;
mod run_state;
mod sensor;

#[cfg(test)]
pub(crate) mod tests;
