//! The stopping rule of provisional answers ([`crate::anytime`]) calibrated into a model's
//! provenance, which the exporter writes into the file: a run's on its own validation windows
//! ([`calibrate_run`]), and a cross-validation's, one rule calibrated on the validation answers of
//! all its PVT³ runs together (each run's model on its own validation fold, thousands of samples where a
//! single run has about 200), written into every run's provenance, so that any of them exports
//! with it (docs/anytime.md, "Calibrated on a cross-validation"). Each run's validation fold is
//! the one it recorded ([`crate::provenance::Provenance::dataset`]); the test fold is never read.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use crate::anytime::Prefixes;
use crate::checkpoint;
use crate::data::windows::Samples;
use crate::data::Dataset;
use crate::json::write_json_atomically;
use crate::provenance::Stopping;
use crate::run_dir::Checkpoint;
use crate::Result;

/// Calibrates the stopping rule of the PVT³ checkpoint in `dir` on the validation samples, into its
/// provenance. Other networks give no provisional answers, and a run with nothing to validate is
/// calibrated by no one here.
pub fn calibrate_run(dir: &Path, val_set: &Samples) -> Result<()> {
    if val_set.is_empty() {
        // A final model takes its cross-validation's rule (`crate::final_model`).
        return Ok(());
    }
    let (mut meta, model, _) = checkpoint::load(dir)?;
    let Some(pvt3) = crate::anytime::answering(&model) else { return Ok(()) };
    meta.provenance.stopping = Some(crate::anytime::prefixes(pvt3, val_set)?.calibrate());
    write_json_atomically(&Checkpoint(dir).provenance(), &meta.provenance)
}

/// Calibrates one rule ([`Prefixes::calibrate_pooled`]) on the validation answers of the runs in
/// `dirs` (run or checkpoint directories of one configuration) and writes it into each run's
/// provenance. `None`, and nothing written, for networks without provisional answers, no runs, or
/// runs of different windows.
pub fn calibrate_together(dirs: &[PathBuf]) -> Result<Option<Stopping>> {
    // One data set per split the runs recorded (the seeds of a set without a fold array each
    // draw their own).
    let mut datasets: HashMap<String, Dataset> = HashMap::new();
    let mut answers = Vec::with_capacity(dirs.len());
    for dir in dirs {
        let (meta, model, _) = checkpoint::load(dir)?;
        let Some(pvt3) = crate::anytime::answering(&model) else { return Ok(None) };
        let p = &meta.provenance;
        let split = p.trained_on.as_ref().map_or_else(|| format!("seed {} {:?}", p.seed, p.held_out), |t| t.folds.clone());
        let data = match datasets.entry(format!("{} {split}", p.data)) {
            std::collections::hash_map::Entry::Occupied(e) => e.into_mut(),
            std::collections::hash_map::Entry::Vacant(e) => e.insert(p.dataset(None)?),
        };
        let val = Samples::new(data, &data.split_for(p.val_fold)?.val, &meta.normalization);
        answers.push(crate::anytime::prefixes(pvt3, &val)?);
    }
    // Runs whose windows differ (each seed's window is its own shortest touch that trains)
    // answer after different tokens: each keeps the rule of its own validation fold.
    if answers.is_empty() || answers.iter().any(|a| a.tokens != answers[0].tokens) {
        return Ok(None);
    }
    let rule = Prefixes::pooled(answers)?.calibrate_pooled(dirs.len());
    for dir in dirs {
        let (checkpoint_dir, mut meta) = checkpoint::load_meta(dir)?;
        meta.provenance.stopping = Some(rule.clone());
        write_json_atomically(&Checkpoint(&checkpoint_dir).provenance(), &meta.provenance)?;
    }
    Ok(Some(rule))
}
