//! Resuming and checkpointing a run, in one place: how a call of `train` opens its output
//! directory and what it saves at the end of each epoch. `last/` holds every sensor's weights,
//! optimiser state and weight average ([`super::learner::Net`]) and the run's state
//! ([`RunState`]), replaced whole at the end of each epoch after the epoch's metrics line;
//! `--resume` continues from it (or returns a finished run's `result.json`) and refuses touches
//! split otherwise than it recorded. The epoch chosen by validation is checkpointed into `model/`
//! as it is validated ([`super::sensor::Sensor::validate`]).

use std::path::{Path, PathBuf};

use indicatif::ProgressBar;
use pvt3_spec::prune::PruneSpec;

use super::epoch::Trained;
use super::sensor::{self, Sensor, Validated};
use super::state::RunState;
use super::{RunResult, RunSpec};
use crate::json::{read_json, write_json};
use crate::metrics::Log;
use crate::options::TrainOptions;
use crate::run_dir::{Checkpoint, Run};
use crate::{atomic, checkpoint};
use crate::{Error, Result};

/// A run ready for the epochs of this call: its sensors, its options (a resumed run keeps those
/// it started with), its state and its metrics logs.
pub(super) struct Training<'a> {
    pub(super) sensors: Vec<Sensor<'a>>,
    pub(super) opts: TrainOptions,
    pub(super) state: RunState,
    logs: Vec<Log>,
    /// The run's `last/`.
    last: PathBuf,
}

/// The result of the finished run of `spec` in `out` when resuming (`resume`) finds one there,
/// checked to be on the same split: a resumed run that has finished answers at once.
pub(super) fn finished(spec: &RunSpec, out: &Path, resume: bool) -> Result<Option<RunResult>> {
    let run_dir = Run(out);
    if !(resume && run_dir.result().exists()) {
        return Ok(None);
    }
    check_resumed_split(spec, &run_dir.model())?;
    read_json(&run_dir.result()).map(Some)
}

/// Opens the unfinished run of `spec` in `out`: with `resume`, the run there restored from its
/// `last/` (checked to be on the same split), or a fresh one where it holds none; without, a
/// fresh run, refused where `out` holds one. Either way, the temporary files a killed run left
/// half-written are removed.
pub(super) fn open<'a>(spec: &RunSpec<'a>, out: &Path, resume: bool, bar: &ProgressBar) -> Result<Training<'a>> {
    let run_dir = Run(out);
    let resumable = atomic::dir::existing_dir(&run_dir.last());
    if !resume && (resumable.is_some() || run_dir.result().exists()) {
        return Err(Error::Usage(format!(
            "{} already holds a run; pass --resume to continue it, or choose another output directory",
            out.display()
        )));
    }
    let (config, opts, last) = match resumable.filter(|_| resume) {
        Some(dir) => {
            check_resumed_split(spec, &dir)?;
            let (_, meta) = checkpoint::load_meta(&dir)?;
            let state = read_json::<RunState>(&Checkpoint(&dir).state())?;
            (meta.config, meta.provenance.options, Some((dir, state)))
        }
        None => (spec.config.clone(), spec.options.clone(), None),
    };
    atomic::file::remove_temporaries(out)?;
    let sensors = sensor::of_run(spec, config, &opts, out, last.as_ref().map(|(dir, state)| (dir.as_path(), state.step)), bar)?;
    let state = last.map_or_else(|| RunState::fresh(&opts), |(_, state)| state);
    let logs = sensors.iter().map(|s| Log::open(&Run(&s.dir).metrics(), state.epochs_done)).collect::<Result<_>>()?;
    Ok(Training { sensors, opts, state, logs, last: run_dir.last() })
}

impl Training<'_> {
    /// Records the end of epoch `epoch`: each sensor's metrics line and training curves, then the
    /// resume state (every sensor's weights, optimiser and average, and the run's state),
    /// replacing `last/` at once. The metrics line before the resume state: a run killed between
    /// the two resumes from the epoch before, whose log it cuts back to (a line after a saved
    /// state would be lost).
    pub(super) fn end_epoch(
        &mut self,
        (epoch, seconds): (usize, f64),
        trained: &Trained,
        validated: &[Validated],
        (val_fold, pruning): (Option<usize>, &Option<PruneSpec>),
    ) -> Result<()> {
        self.state.wall_seconds += seconds;
        self.state.epochs_done = epoch;
        for (i, ((sensor, log), (tally, val))) in
            self.sensors.iter().zip(&mut self.logs).zip(trained.tallies.iter().zip(validated)).enumerate()
        {
            log.append(&trained.line(epoch, seconds, tally, val))?;
            crate::plot::curves::write_run(&sensor.dir, self.state.best_of(i).as_ref().map(|b| b.epoch))?;
        }
        crate::crash::point("logged");
        let (sensors, state) = (&self.sensors, &self.state);
        atomic::dir::replace_dir(&self.last, |dir| {
            for (i, (sensor, val)) in sensors.iter().zip(validated).enumerate() {
                let sub = Checkpoint(dir).of_sensor(i);
                std::fs::create_dir_all(&sub).map_err(Error::io(&sub))?;
                sensor.net.save_last(&sub, &sensor.meta(val_fold, pruning, epoch, val.accuracy, None))?;
            }
            write_json(&Checkpoint(dir).state(), state)
        })?;
        crate::crash::point("saved");
        Ok(())
    }
}

/// Refuses to continue the run whose checkpoint is `dir` (and its partner's) on data split
/// otherwise than it recorded, naming what differs (another file, another seed's folds, other
/// held-out levels).
fn check_resumed_split(spec: &RunSpec, dir: &Path) -> Result<()> {
    let partner = spec.partner.as_ref().map(|p| (p.data, Checkpoint(dir).partner()));
    for (data, checkpoint) in std::iter::once((spec.data, dir.to_path_buf())).chain(partner) {
        let Some(existing) = atomic::dir::existing_dir(&checkpoint) else { continue };
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
