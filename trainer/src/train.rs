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
use std::path::{Path, PathBuf};
use std::time::Instant;

use indicatif::ProgressBar;
use pvt3_models::{Config, Rng};
use pvt3_spec::prune::PruneSpec;
use pvt3_spec::weights::Tensors;
use serde::{Deserialize, Serialize};

use crate::checkpoint::{self, nan_from_null, read_json, write_json, write_json_atomically};
use crate::data::windows::Samples;
use crate::data::Dataset;
use crate::joint::Partner;
use crate::optim::is_weight_matrix;
use crate::options::TrainOptions;
use crate::run_dir::{Checkpoint, Run};
use crate::schedule::Schedule;
use crate::{Error, Result};
use learner::is_mask;
pub use learner::Learner;
use sensor::{Sensor, Validated};
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
}

/// What `last/state.json` remembers between epochs.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct RunState {
    epochs_done: usize,
    step: usize,
    rng: Rng,
    best: Option<Best>,
    /// A joint run's: the partner network's best epoch so far.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    partner_best: Option<Best>,
    wall_seconds: f64,
}

impl RunState {
    /// The best epoch so far of the run's sensor `i` (0: the run's own, 1: a joint run's other).
    fn best_of(&mut self, i: usize) -> &mut Option<Best> {
        if i == 0 {
            &mut self.best
        } else {
            &mut self.partner_best
        }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
struct Best {
    epoch: usize,
    #[serde(deserialize_with = "nan_from_null")]
    val_accuracy: f64,
    #[serde(deserialize_with = "nan_from_null")]
    val_loss: f64,
    #[serde(deserialize_with = "nan_from_null")]
    test_accuracy: f64,
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
    let run_dir = Run(out);
    if resume && run_dir.result().exists() {
        check_resumed_split(spec, &run_dir.model())?;
        return read_json(&run_dir.result()).map(Some);
    }
    let resumable = checkpoint::existing_dir(&run_dir.last());
    if !resume && (resumable.is_some() || run_dir.result().exists()) {
        return Err(Error::Usage(format!(
            "{} already holds a run; pass --resume to continue it, or choose another output directory",
            out.display()
        )));
    }
    let (config, opts, state) = match resumable.filter(|_| resume) {
        Some(dir) => resumed(spec, dir)?,
        None => (spec.config.clone(), spec.options.clone(), None),
    };
    let mut sensors = sensors(spec, config, &opts, out)?;
    let steps_per_epoch = sensors[0].split.train.len().div_ceil(opts.optimization.batch_size);
    let schedule = Schedule::new(&opts.optimization, steps_per_epoch);
    let mut run = start(&mut sensors, spec, &opts, state)?;
    bar.set_length((opts.optimization.epochs * steps_per_epoch) as u64);
    bar.set_position((run.epochs_done * steps_per_epoch) as u64);
    let mut logs = sensors.iter().map(|s| open_log(&Run(&s.dir).metrics())).collect::<Result<Vec<_>>>()?;
    let first_epoch = run.epochs_done + 1;
    for epoch in first_epoch..=opts.optimization.epochs {
        if stalled(&mut run, sensors.len(), opts.optimization.patience) {
            break;
        }
        if spec.pause_after.is_some_and(|p| epoch - first_epoch >= p) {
            return Ok(None);
        }
        let started = Instant::now();
        let trained = epoch::train(&mut sensors, epoch, &schedule, &opts, &mut run, bar)?;
        // With weight averaging, the average is what is evaluated, selected and checkpointed.
        let validated = (sensors.iter_mut().enumerate())
            .map(|(i, s)| s.validate(epoch, run.best_of(i), (spec.val_fold, &spec.pruning)))
            .collect::<Result<Vec<_>>>()?;
        let seconds = started.elapsed().as_secs_f64();
        run.wall_seconds += seconds;
        run.epochs_done = epoch;
        save_last(&sensors, &run_dir.last(), &run, (spec.val_fold, &spec.pruning), (epoch, &validated))?;
        for ((sensor, log), (tally, val)) in sensors.iter().zip(&mut logs).zip(trained.tallies.iter().zip(&validated)) {
            let line = trained.line(epoch, seconds, tally, val);
            writeln!(log, "{}", serde_json::to_string(&line).expect("plain data")).map_err(Error::io(&sensor.dir))?;
            crate::plot::curves::write_run(&sensor.dir)?;
        }
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

/// Whether `--patience` stops the run after its epochs done: every sensor's validation has not
/// improved for that many epochs. Asked before an epoch, not after, so that a run interrupted
/// after its last epoch stops where it would have.
fn stalled(run: &mut RunState, sensors: usize, patience: Option<usize>) -> bool {
    let Some(patience) = patience.filter(|p| *p > 0) else { return false };
    let done = run.epochs_done;
    (0..sensors).all(|i| run.best_of(i).as_ref().is_some_and(|b| done >= b.epoch + patience))
}

/// The configuration, options and state of the run to resume from its checkpoint `dir` (a
/// `last/`): a resumed run keeps the configuration and options it started with.
fn resumed(spec: &RunSpec, dir: PathBuf) -> Result<(Config, TrainOptions, Option<(PathBuf, RunState)>)> {
    check_resumed_split(spec, &dir)?;
    let (_, meta) = checkpoint::load_meta(&dir)?;
    let state = read_json::<RunState>(&Checkpoint(&dir).state())?;
    Ok((meta.config, meta.provenance.options, Some((dir, state))))
}

/// The run's sensors, each with its options and run directory (made here): the run's own, its
/// teachers loaded (`--distill`), and a joint run's other sensor.
fn sensors<'a>(spec: &RunSpec<'a>, config: Config, opts: &TrainOptions, out: &Path) -> Result<Vec<Sensor<'a>>> {
    let mut main = Sensor::new(spec.data, config, spec.classes.clone(), (spec.val_fold, opts), out, (spec.start.as_ref(), None))?;
    let mut sensors = Vec::new();
    if let Some(p) = &spec.partner {
        p.check(main.data, &main.config, &main.classes, opts)?;
        let share = opts.joint.as_ref().is_some_and(|j| j.share_temporal).then_some(&main.net.learner.varmap);
        let options = Partner::options(opts, spec.data);
        let dir = Run(out).partner();
        sensors.push(Sensor::new(p.data, p.config.clone(), p.classes.clone(), (spec.val_fold, &options), &dir, (None, share))?);
    }
    if let Some(teachers) = &opts.distillation.teachers {
        let trained_on = (spec.val_fold, &main.data.trained_on());
        let teachers = crate::distill::Teachers::load(Path::new(teachers), trained_on, &main.normalization, &main.classes, out)?;
        main.net.learner.teachers = Some(teachers);
    }
    sensors.insert(0, main);
    for sensor in &sensors {
        std::fs::create_dir_all(&sensor.dir).map_err(Error::io(&sensor.dir))?;
    }
    Ok(sensors)
}

/// The run's state at its first epoch: restored from `state` when resuming, otherwise fresh (the
/// spectral heads fitted, the metrics logs cleared); then the zeros that fine-tuning holds.
fn start(sensors: &mut [Sensor], spec: &RunSpec, opts: &TrainOptions, state: Option<(PathBuf, RunState)>) -> Result<RunState> {
    let run = match state {
        Some((dir, state)) => {
            for (i, sensor) in sensors.iter_mut().enumerate() {
                sensor.restore(&in_last(&dir, i), state.step)?;
                truncate_metrics(&Run(&sensor.dir).metrics(), state.epochs_done)?;
            }
            state
        }
        None => {
            // A run from given weights (fine-tuning) keeps its spectral heads as they are, unless
            // it prunes patches a head over the image's space read: it now reads them as 0.
            let prunes_pixels = spec.config.spectral_space() && spec.pruning.as_ref().is_some_and(|p| p.patches > 0.0);
            if spec.start.is_none() || prunes_pixels {
                for sensor in sensors.iter() {
                    crate::spectrum_fit::fit(&sensor.net.learner.model, &sensor.net.learner.varmap, &sensor.train_set, &sensor.val_set)?;
                }
            }
            for sensor in sensors.iter() {
                let _ = std::fs::remove_file(Run(&sensor.dir).metrics());
            }
            let rng = Rng::new(opts.seed.wrapping_add(1));
            RunState { epochs_done: 0, step: 0, rng, best: None, partner_best: None, wall_seconds: 0.0 }
        }
    };
    for sensor in sensors.iter_mut() {
        if opts.held.pruned {
            sensor.net.learner.hold_zeros(is_mask)?;
        }
        if opts.held.zero_weights {
            sensor.net.learner.hold_zeros(is_weight_matrix)?;
        }
    }
    Ok(run)
}

/// Where sensor `i`'s resume state lives in the run's `last/` directory `dir`.
fn in_last(dir: &Path, i: usize) -> PathBuf {
    if i == 0 {
        dir.to_path_buf()
    } else {
        Checkpoint(dir).partner()
    }
}

/// The end of an epoch's resume state: every sensor's weights, optimiser and average, and the
/// run's state, replacing `last` at once.
fn save_last(
    sensors: &[Sensor],
    last: &Path,
    run: &RunState,
    (val_fold, pruning): (Option<usize>, &Option<PruneSpec>),
    (epoch, validated): (usize, &[Validated]),
) -> Result<()> {
    checkpoint::replace_dir(last, |dir| {
        for (i, (sensor, val)) in sensors.iter().zip(validated).enumerate() {
            let sub = in_last(dir, i);
            std::fs::create_dir_all(&sub).map_err(Error::io(&sub))?;
            sensor.save_last(&sub, &sensor.meta(val_fold, pruning, epoch, val.accuracy, None))?;
        }
        write_json(&Checkpoint(dir).state(), run)
    })
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

/// Refuses to continue the run whose checkpoint is `dir` (and its partner's) on data split
/// otherwise than it recorded, naming what differs (another file, another seed's folds, other
/// held-out levels).
fn check_resumed_split(spec: &RunSpec, dir: &Path) -> Result<()> {
    let partner = spec.partner.as_ref().map(|p| (p.data, Checkpoint(dir).partner()));
    for (data, checkpoint) in std::iter::once((spec.data, dir.to_path_buf())).chain(partner) {
        let Some(existing) = checkpoint::existing_dir(&checkpoint) else { continue };
        let (_, meta) = checkpoint::load_meta(&existing)?;
        if let Some(recorded) = &meta.provenance.trained_on {
            let held = |h: Option<&crate::data::HoldOut>| h.map_or("no held-out levels".to_string(), |h| format!("held out {h}"));
            data.check_split(
                recorded,
                &format!(
                    "the run in {} (seed {}, {}; this command: {})",
                    existing.display(),
                    meta.provenance.seed,
                    held(meta.provenance.held_out.as_ref()),
                    held(data.held_out.as_ref())
                ),
            )?;
        }
    }
    Ok(())
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

/// Keeps the first `epochs` lines of a metrics log (a crash may have left one more).
fn truncate_metrics(path: &Path, epochs: usize) -> Result<()> {
    let Ok(text) = std::fs::read_to_string(path) else {
        return Ok(());
    };
    let kept: String = text.lines().take(epochs).map(|l| format!("{l}\n")).collect();
    std::fs::write(path, kept).map_err(Error::io(path))
}

mod epoch;
mod learner;
pub mod loss;
mod sensor;

#[cfg(test)]
pub(crate) mod tests;
