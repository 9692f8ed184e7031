//! A cross-validation's stopping rule: one rule calibrated on the validation answers of all its
//! PVT³ runs together (each run's model on its own validation fold, thousands of samples where a
//! single run has about 200), written into every run's provenance, so that any of them exports
//! with it (docs/anytime.md, "Calibrated on a cross-validation"). The test fold is never read.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use crate::anytime::{Prefixes, Stopping};
use crate::checkpoint::{self, write_json_atomically};
use crate::data::Dataset;
use crate::evaluate::Samples;
use crate::run_dir::Checkpoint;
use crate::Result;

/// Calibrates one rule ([`Prefixes::calibrate_pooled`]) on the validation answers of the runs in
/// `dirs` (run or checkpoint directories of one configuration) and writes it into each run's
/// provenance. `None`, and nothing written, for networks without provisional answers or no runs.
pub fn calibrate_together(dirs: &[PathBuf]) -> Result<Option<Stopping>> {
    let mut datasets: HashMap<(String, u64), Dataset> = HashMap::new();
    let mut answers = Vec::with_capacity(dirs.len());
    for dir in dirs {
        let (meta, model, _) = checkpoint::load(dir)?;
        let Some(pvt3) = crate::anytime::answering(&model) else { return Ok(None) };
        let key = (meta.provenance.data.clone(), meta.provenance.seed);
        let data = match datasets.entry(key) {
            std::collections::hash_map::Entry::Occupied(e) => e.into_mut(),
            std::collections::hash_map::Entry::Vacant(e) => {
                let data = Dataset::load(Path::new(&e.key().0), e.key().1)?;
                e.insert(data)
            }
        };
        let val = Samples::new(data, &data.split(meta.provenance.val_fold)?.val, &meta.normalization);
        answers.push(crate::anytime::prefixes(pvt3, &val)?);
    }
    if answers.is_empty() {
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
