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

use std::path::Path;
use std::time::Instant;

use indicatif::ProgressBar;
use pvt3_models::Config;
use pvt3_spec::prune::PruneSpec;
use pvt3_spec::weights::Tensors;
use serde::{Deserialize, Serialize};

use crate::data::Dataset;
use crate::joint::Partner;
use crate::json::{nan_from_null, write_json};
use crate::options::TrainOptions;
use crate::run_dir::Run;
use crate::schedule::Schedule;
use crate::{Error, Result};
pub use learner::Learner;
use sensor::Sensor;
use state::RunState;
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
    if let Some(result) = resume::finished(spec, out, resume)? {
        return Ok(Some(result));
    }
    let mut run = resume::open(spec, out, resume, bar)?;
    let opts = run.opts.clone();
    let steps_per_epoch = run.sensors[0].split.train.len().div_ceil(opts.optimization.batch_size);
    let schedule = Schedule::new(&opts.optimization, steps_per_epoch);
    bar.set_length((opts.optimization.epochs * steps_per_epoch) as u64);
    bar.set_position((run.state.epochs_done * steps_per_epoch) as u64);
    let first_epoch = run.state.epochs_done + 1;
    for epoch in first_epoch..=opts.optimization.epochs {
        if run.state.stalled(run.sensors.len(), opts.optimization.patience) {
            break;
        }
        if spec.pause_after.is_some_and(|p| epoch - first_epoch >= p) {
            return Ok(None);
        }
        let started = Instant::now();
        let trained = epoch::train(&mut run.sensors, epoch, &schedule, &opts, &mut run.state, bar)?;
        crate::crash::point("stepped");
        // With weight averaging, the average is what is evaluated, selected and checkpointed.
        let validated = (run.sensors.iter_mut().enumerate())
            .map(|(i, s)| s.validate(epoch, run.state.best_of(i), (spec.val_fold, &spec.pruning)))
            .collect::<Result<Vec<_>>>()?;
        crate::crash::point("validated");
        run.end_epoch((epoch, started.elapsed().as_secs_f64()), &trained, &validated, (spec.val_fold, &spec.pruning))?;
        let (tally, best) = (&trained.tallies[0], run.state.best.as_ref().expect("set after the first epoch"));
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
    finish(&run.sensors, spec, &opts, &mut run.state).map(Some)
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
        crate::stopping::calibrate_run(&Run(&sensor.dir).model(), &sensor.val_set)?;
        write_json(&Run(&sensor.dir).result(), &done)?;
        result = Some(done);
    }
    Ok(result.expect("a run has its own sensor"))
}

mod epoch;
mod learner;
pub mod loss;
mod resume;
mod sensor;
mod state;

#[cfg(test)]
pub(crate) mod tests;
