//! A run's `metrics.jsonl`: one line per finished epoch, appended before the epoch's resume state
//! is saved, so that a run killed between the two resumes from the epoch before, whose log it cuts
//! back to ([`Log::open`]).

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::{Error, Result};

/// One line of `metrics.jsonl`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EpochMetrics {
    pub epoch: usize,
    pub lr: f64,
    pub train_loss: f64,
    pub train_accuracy: f64,
    /// NaN (`null`) where nothing validates (a final model).
    #[serde(deserialize_with = "crate::json::nan_from_null")]
    pub val_loss: f64,
    #[serde(deserialize_with = "crate::json::nan_from_null")]
    pub val_accuracy: f64,
    /// Measured only at the epochs that improved on validation (the candidates).
    pub test_accuracy: Option<f64>,
    pub seconds: f64,
    /// A joint run's (`--joint`): the mean squared difference between the two networks'
    /// encodings of the paired training touches, whether or not it was in the loss yet.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub encodings_apart: Option<f64>,
}

/// Every epoch of the log at `path`, in order; a malformed line is an error naming it.
pub fn read(path: &Path) -> Result<Vec<EpochMetrics>> {
    let text = std::fs::read_to_string(path).map_err(Error::io(path))?;
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| {
            serde_json::from_str(l).map_err(|e| Error::Checkpoint { path: path.to_path_buf(), reason: format!("line {}: {e}", i + 1) })
        })
        .collect()
}

/// A run's metrics log, open to append its epochs.
pub struct Log {
    path: PathBuf,
    file: File,
}

impl Log {
    /// Opens the log at `path` to append the epochs after its first `epochs`: a fresh run's
    /// (`epochs` = 0) starts empty, and a resumed run's keeps the epochs its state holds (a crash
    /// may have left one line more).
    pub fn open(path: &Path, epochs: usize) -> Result<Self> {
        let kept: String = match std::fs::read_to_string(path) {
            Ok(text) => text.lines().take(epochs).map(|l| format!("{l}\n")).collect(),
            Err(_) => String::new(),
        };
        std::fs::write(path, kept).map_err(Error::io(path))?;
        let file = std::fs::OpenOptions::new().append(true).open(path).map_err(Error::io(path))?;
        Ok(Self { path: path.to_path_buf(), file })
    }

    /// Appends an epoch's line.
    pub fn append(&mut self, line: &EpochMetrics) -> Result<()> {
        writeln!(self.file, "{}", serde_json::to_string(line).expect("plain data")).map_err(Error::io(&self.path))
    }
}
