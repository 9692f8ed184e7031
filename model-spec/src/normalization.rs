//! Per-channel normalisation of raw sensor values (a channel is one taxel or electrode, and one
//! colour of it): plain data stored with every checkpoint, so that evaluation and export apply
//! the very numbers training used. Fitting it is the trainer's business.

use serde::{Deserialize, Serialize};

use crate::config::Config;

/// `(x - mean[c]) / std[c]` for every channel `c`; samples are laid out `[channels…, frames]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Normalization {
    pub mean: Vec<f32>,
    pub std: Vec<f32>,
    pub frames: usize,
}

impl Normalization {
    /// Whether this normalises the windows `config` reads: a mean and a deviation for each of its
    /// sensor channels, fitted for its frames.
    pub fn fits(&self, config: &Config) -> bool {
        let channels = config.sensor_channels();
        self.mean.len() == channels && self.std.len() == channels && self.frames == config.frames
    }

    /// Appends the normalised `sample` to `out`.
    pub fn apply_into(&self, sample: &[f32], out: &mut Vec<f32>) {
        for (c, row) in sample.chunks(self.frames).enumerate() {
            let (m, s) = (self.mean[c], self.std[c]);
            out.extend(row.iter().map(|v| (v - m) / s));
        }
    }
}
