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
//! `pvt3 cv --out DIR` writes one run directory per seed and fold, [`CV_SUMMARY`] and
//! [`CV_CURVES`] (and a joint one [`CV_PARTNER_CURVES`]).

use std::path::{Path, PathBuf};

/// The summary of a cross-validation, in its directory.
pub const CV_SUMMARY: &str = "cv.json";

/// The figure of a cross-validation's runs, in its directory.
pub const CV_CURVES: &str = "cv-curves.svg";

/// A joint cross-validation's (`--joint`): the figure of the other sensor's runs.
pub const CV_PARTNER_CURVES: &str = "cv-partner-curves.svg";

/// A joint run's partner (`--joint`): inside a run directory, the other sensor's run directory;
/// inside its `last/`, that run's resume state.
pub const PARTNER: &str = "partner";

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

    /// `last/` only: where the run stands (epochs done, the best so far, the random state).
    pub fn state(self) -> PathBuf {
        self.0.join("state.json")
    }
}
