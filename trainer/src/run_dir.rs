//! The files of a run directory, named once. `pvt3 train --out DIR` writes:
//!
//! - `model/`, the checkpoint of the epoch chosen by validation ([`Checkpoint`]: configuration,
//!   normalisation, class names, provenance, weights);
//! - `last/`, the checkpoint of the last finished epoch, with what resuming needs besides: the
//!   optimiser's state, the run's state and, when averaging, the weight average;
//! - `metrics.jsonl`, one line per epoch, and `result.json` once the run has finished;
//! - `curves.svg`, the training curves, redrawn after every epoch;
//! - `pruned/`, a run directory of its own: the pruned and fine-tuned model;
//! - `partner/`, a joint run's (`--joint`): the other sensor's run directory.
//!
//! `pvt3 cv --out DIR` writes one run directory per seed and fold ([`CrossValidation`]),
//! [`CV_SUMMARY`] and [`CV_CURVES`] (and a joint one [`CV_PARTNER_CURVES`]); `pvt3 final` adds
//! the run directory [`FINAL`].

use std::fmt::Display;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use crate::{Error, Result};

/// The summary of a cross-validation, in its directory.
pub const CV_SUMMARY: &str = "cv.json";

/// The figure of a cross-validation's runs, in its directory.
pub const CV_CURVES: &str = "cv-curves.svg";

/// A joint cross-validation's (`--joint`): the figure of the other sensor's runs.
pub const CV_PARTNER_CURVES: &str = "cv-partner-curves.svg";

/// A cross-validation's final model (`pvt3 final`): inside its directory, the run directory of
/// the model trained on every touch as the cross-validation chose.
pub const FINAL: &str = "final";

/// A joint run's partner (`--joint`): inside a run directory, the other sensor's run directory;
/// inside its `last/`, that run's resume state.
pub const PARTNER: &str = "partner";

/// A cross-validation's directory: the run of seed `S` with validation fold `K` in `seed{S}/fold{K}/`.
#[derive(Clone, Copy, Debug)]
pub struct CrossValidation<'a>(pub &'a Path);

impl CrossValidation<'_> {
    /// The run of `seed` with validation fold `fold`.
    pub fn run(self, seed: u64, fold: usize) -> PathBuf {
        self.0.join(format!("seed{seed}")).join(format!("fold{fold}"))
    }

    /// Every run directory in it, as `(seed, fold, directory)`, by seed and then fold.
    pub fn runs(self) -> Result<Vec<(u64, usize, PathBuf)>> {
        let mut runs = Vec::new();
        for (seed, seed_dir) in numbered(self.0, "seed")? {
            runs.extend(numbered(&seed_dir, "fold")?.into_iter().map(|(fold, dir)| (seed, fold, dir)));
        }
        Ok(runs)
    }
}

/// The directories in `dir` named `prefix` and a number as [`CrossValidation::run`] writes it
/// (`seed3`, `fold0`), by number.
fn numbered<N: FromStr + Display + Ord>(dir: &Path, prefix: &str) -> Result<Vec<(N, PathBuf)>> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(Error::io(dir))? {
        let path = entry.map_err(Error::io(dir))?.path();
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or_default();
        let number = name.strip_prefix(prefix).and_then(|n| n.parse::<N>().ok());
        if let Some(n) = number.filter(|n| format!("{prefix}{n}") == name && path.is_dir()) {
            found.push((n, path));
        }
    }
    found.sort_by(|a, b| a.0.cmp(&b.0));
    Ok(found)
}

/// A run directory.
#[derive(Clone, Copy, Debug)]
pub struct Run<'a>(pub &'a Path);

impl Run<'_> {
    /// The checkpoint of the selected epoch.
    pub fn model(self) -> PathBuf {
        self.0.join("model")
    }

    /// The checkpoint of the last finished epoch, to resume from.
    pub fn last(self) -> PathBuf {
        self.0.join("last")
    }

    pub fn metrics(self) -> PathBuf {
        self.0.join("metrics.jsonl")
    }

    /// The training curves (`crate::plot::curves`).
    pub fn curves(self) -> PathBuf {
        self.0.join("curves.svg")
    }

    /// What a camera head's fit chose (`crate::spectrum_fit::Chosen`), written once it is fitted.
    pub fn head(self) -> PathBuf {
        self.0.join("head.json")
    }

    /// Written when the run has finished: a finished run is one with this file.
    pub fn result(self) -> PathBuf {
        self.0.join("result.json")
    }

    /// The pruned and fine-tuned model's run directory.
    pub fn pruned(self) -> PathBuf {
        self.0.join("pruned")
    }

    /// A joint run's other sensor: its run directory.
    pub fn partner(self) -> PathBuf {
        self.0.join(PARTNER)
    }
}

/// A checkpoint directory: `model/` or `last/` of a run.
#[derive(Clone, Copy, Debug)]
pub struct Checkpoint<'a>(pub &'a Path);

impl Checkpoint<'_> {
    /// The model's configuration; a directory with this file is a checkpoint.
    pub fn config(self) -> PathBuf {
        self.0.join("config.json")
    }

    pub fn normalization(self) -> PathBuf {
        self.0.join("normalization.json")
    }

    pub fn classes(self) -> PathBuf {
        self.0.join("classes.json")
    }

    pub fn provenance(self) -> PathBuf {
        self.0.join("provenance.json")
    }

    pub fn weights(self) -> PathBuf {
        self.0.join("weights.safetensors")
    }

    /// `last/` only: the optimiser's moments.
    pub fn optimizer(self) -> PathBuf {
        self.0.join("optimizer.safetensors")
    }

    /// `last/` only: the weight average, when the run averages.
    pub fn average(self) -> PathBuf {
        self.0.join("average.safetensors")
    }

    /// `last/` of a joint run only: the other sensor's resume state, a checkpoint of its own.
    pub fn partner(self) -> PathBuf {
        self.0.join(PARTNER)
    }

    /// `last/` only: where the run's sensor `i` keeps its resume state (0: the run's own, in
    /// `last/` itself; 1: a joint run's other, [`Checkpoint::partner`]).
    pub fn of_sensor(self, i: usize) -> PathBuf {
        if i == 0 {
            self.0.to_path_buf()
        } else {
            self.partner()
        }
    }

    /// `last/` only: where the run stands (epochs done, the best so far, the random state).
    pub fn state(self) -> PathBuf {
        self.0.join("state.json")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cross_validation_lists_the_runs_it_names_by_number() {
        let out = crate::train::tests::out_dir("cross-validation");
        for (seed, fold) in [(10, 0), (2, 3), (2, 1)] {
            std::fs::create_dir_all(CrossValidation(&out).run(seed, fold)).unwrap();
        }
        // Not runs: a name pvt3 never writes, a file, a folder that is no fold.
        for odd in ["seed01/fold0", "seed2/fold2.old", "seedx/fold0"] {
            std::fs::create_dir_all(out.join(odd)).unwrap();
        }
        std::fs::write(out.join("seed2/fold4"), "").unwrap();
        let runs: Vec<_> =
            CrossValidation(&out).runs().unwrap().into_iter().map(|(s, f, d)| (s, f, d.strip_prefix(&out).unwrap().to_owned())).collect();
        let expected: Vec<_> = [(2, 1), (2, 3), (10, 0)].map(|(s, f)| (s, f, PathBuf::from(format!("seed{s}/fold{f}")))).into();
        assert_eq!(runs, expected);
        std::fs::remove_dir_all(&out).unwrap();
    }
}
