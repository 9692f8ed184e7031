//! A run's state between epochs and how a call of `train` picks it up: `last/` holds every
//! sensor's weights, optimiser state and weight average and the run's counters and best epochs
//! (`state.json`), replaced whole at the end of each epoch; `--resume` continues from it (or
//! returns a finished run's `result.json`) and refuses touches split otherwise than it recorded.

use std::path::{Path, PathBuf};

use pvt3_models::{Config, Rng};
use pvt3_spec::prune::PruneSpec;
use serde::{Deserialize, Serialize};

use super::sensor::{Best, Sensor, Validated};
use super::{RunResult, RunSpec};
use crate::checkpoint::{self, read_json, write_json, Meta};
use crate::options::TrainOptions;
use crate::run_dir::{Checkpoint, Run};
use crate::{Error, Result};

/// What `last/state.json` remembers between epochs.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct RunState {
    pub(super) epochs_done: usize,
    pub(super) step: usize,
    pub(super) rng: Rng,
    pub(super) best: Option<Best>,
    /// A joint run's: the partner network's best epoch so far.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) partner_best: Option<Best>,
    pub(super) wall_seconds: f64,
}

impl RunState {
    /// A run's state before its first epoch: its draws seeded from the options' seed.
    fn fresh(opts: &TrainOptions) -> Self {
        let rng = Rng::new(opts.seed.wrapping_add(1));
        Self { epochs_done: 0, step: 0, rng, best: None, partner_best: None, wall_seconds: 0.0 }
    }

    /// The best epoch so far of the run's sensor `i` (0: the run's own, 1: a joint run's other).
    pub(super) fn best_of(&mut self, i: usize) -> &mut Option<Best> {
        if i == 0 {
            &mut self.best
        } else {
            &mut self.partner_best
        }
    }

    /// Whether `--patience` stops the run after its epochs done: every sensor's validation has
    /// not improved for that many epochs. Asked before an epoch, not after, so that a run
    /// interrupted after its last epoch stops where it would have.
    pub(super) fn stalled(&mut self, sensors: usize, patience: Option<usize>) -> bool {
        let Some(patience) = patience.filter(|p| *p > 0) else { return false };
        let done = self.epochs_done;
        (0..sensors).all(|i| self.best_of(i).as_ref().is_some_and(|b| done >= b.epoch + patience))
    }
}

/// What a call of `train` finds in its output directory.
pub(super) enum Found {
    /// A finished run (with `--resume`): its result.
    Finished(RunResult),
    /// The run to train: its configuration and options (a resumed run keeps those it started
    /// with) and, when resuming, its `last/` directory and state.
    Run { config: Config, opts: TrainOptions, last: Option<(PathBuf, RunState)> },
}

/// What `out` holds for a run of `spec`: with `resume`, the run there (finished or not), checked
/// to be on the same split; without, nothing, or the run is refused.
pub(super) fn find(spec: &RunSpec, out: &Path, resume: bool) -> Result<Found> {
    let run_dir = Run(out);
    if resume && run_dir.result().exists() {
        check_resumed_split(spec, &run_dir.model())?;
        return read_json(&run_dir.result()).map(Found::Finished);
    }
    let resumable = checkpoint::existing_dir(&run_dir.last());
    if !resume && (resumable.is_some() || run_dir.result().exists()) {
        return Err(Error::Usage(format!(
            "{} already holds a run; pass --resume to continue it, or choose another output directory",
            out.display()
        )));
    }
    match resumable.filter(|_| resume) {
        Some(dir) => {
            check_resumed_split(spec, &dir)?;
            let (_, meta) = checkpoint::load_meta(&dir)?;
            let state = read_json::<RunState>(&Checkpoint(&dir).state())?;
            Ok(Found::Run { config: meta.config, opts: meta.provenance.options, last: Some((dir, state)) })
        }
        None => Ok(Found::Run { config: spec.config.clone(), opts: spec.options.clone(), last: None }),
    }
}

/// The run's state at its first epoch: restored with every sensor's network from `last` when
/// resuming (each metrics log cut to the epochs done), otherwise fresh (the logs removed). Either
/// way, the temporary files a killed run left half-written are removed.
pub(super) fn begin(sensors: &mut [Sensor], opts: &TrainOptions, last: Option<(PathBuf, RunState)>) -> Result<RunState> {
    for sensor in sensors.iter() {
        checkpoint::remove_temporaries(&sensor.dir)?;
    }
    let Some((dir, state)) = last else {
        for sensor in sensors.iter() {
            let _ = std::fs::remove_file(Run(&sensor.dir).metrics());
        }
        return Ok(RunState::fresh(opts));
    };
    for (i, sensor) in sensors.iter_mut().enumerate() {
        sensor.restore(&in_last(&dir, i), state.step)?;
        truncate_metrics(&Run(&sensor.dir).metrics(), state.epochs_done)?;
    }
    Ok(state)
}

/// The end of an epoch's resume state: every sensor's weights, optimiser and average, and the
/// run's state, replacing `last` at once.
pub(super) fn save_last(
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

impl Sensor<'_> {
    /// The weights, optimiser state and weight average of the checkpoint `dir` (a `last/`).
    fn restore(&mut self, dir: &Path, step: usize) -> Result<()> {
        pvt3_models::weights::load_weights(&self.net.learner.varmap, &Checkpoint(dir).weights())?;
        self.net.learner.optimizer.load(&Checkpoint(dir).optimizer(), step)?;
        if let Some(average) = &mut self.net.average {
            average.load(&Checkpoint(dir).average())?;
        }
        Ok(())
    }

    /// Writes the resume state of this sensor's network into `dir` (a `last/` being filled).
    fn save_last(&self, dir: &Path, meta: &Meta) -> Result<()> {
        checkpoint::write_files(dir, &self.net.learner.varmap, meta)?;
        let files = Checkpoint(dir);
        self.net.learner.optimizer.save(&files.optimizer())?;
        if let Some(average) = &self.net.average {
            average.save(&files.average())?;
        }
        Ok(())
    }
}

/// Where sensor `i`'s resume state lives in the run's `last/` directory `dir`.
fn in_last(dir: &Path, i: usize) -> PathBuf {
    if i == 0 {
        dir.to_path_buf()
    } else {
        Checkpoint(dir).partner()
    }
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

/// Keeps the first `epochs` lines of a metrics log (a crash may have left one more).
fn truncate_metrics(path: &Path, epochs: usize) -> Result<()> {
    let Ok(text) = std::fs::read_to_string(path) else {
        return Ok(());
    };
    let kept: String = text.lines().take(epochs).map(|l| format!("{l}\n")).collect();
    std::fs::write(path, kept).map_err(Error::io(path))
}
