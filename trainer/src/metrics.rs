//! A run's `metrics.jsonl`: one line per finished epoch.

use std::path::Path;

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
    #[serde(deserialize_with = "crate::provenance::nan_from_null")]
    pub val_loss: f64,
    #[serde(deserialize_with = "crate::provenance::nan_from_null")]
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
