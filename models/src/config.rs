//! The model configuration, with named presets for the supported sensors.
//!
//! Every size is configurable. Inputs are `[batch, height, width, frames]` for single-channel
//! sensors and `[batch, height, width, channels, frames]` otherwise. A temporal patch (`tubelet`)
//! groups consecutive frames into one token, so that long recordings train in reasonable time;
//! the frame-selection mask then has one entry per tubelet.

use serde::{Deserialize, Serialize};

use crate::{Error, Result};

/// The names accepted by [`Config::preset`].
pub const PRESETS: [&str; 3] = ["icub20", "biotac20", "gelsight"];

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Config {
    /// Sensor grid rows (taxels or electrodes).
    pub height: usize,
    /// Sensor grid columns.
    pub width: usize,
    /// Values per taxel and frame (3 for RGB).
    pub channels: usize,
    /// Frames in one input window.
    pub frames: usize,
    pub patch_height: usize,
    pub patch_width: usize,
    /// Frames per temporal token.
    pub tubelet: usize,
    /// Embedding width.
    pub dim: usize,
    pub space_depth: usize,
    pub time_depth: usize,
    pub heads: usize,
    pub dim_head: usize,
    /// Feed-forward hidden width.
    pub mlp_dim: usize,
    pub classes: usize,
    /// Dropout probability used while training (embedding, attention output, feed-forward).
    #[serde(default)]
    pub dropout: f64,
    #[serde(default = "default_eps")]
    pub layer_norm_eps: f64,
}

fn default_eps() -> f64 {
    1e-5
}

impl Config {
    /// The iCub forearm skin preset of DESIGN.md: 6 × 10 taxels, 75 frames, 20 classes,
    /// exactly 64,272 trainable parameters besides the frame mask.
    pub fn icub20() -> Self {
        Self {
            height: 6,
            width: 10,
            channels: 1,
            frames: 75,
            patch_height: 3,
            patch_width: 5,
            tubelet: 1,
            dim: 20,
            space_depth: 4,
            time_depth: 4,
            heads: 1,
            dim_head: 64,
            mlp_dim: 40,
            classes: 20,
            dropout: 0.0,
            layer_norm_eps: 1e-5,
        }
    }

    /// BioTac: 19 electrodes with no regular grid, 400 frames. Each electrode is its own
    /// spatial token (a 19 × 1 grid, patch 1 × 1) and 10 consecutive frames form one temporal
    /// token, so the spatial transformer attends across electrodes over 40 time steps.
    pub fn biotac20() -> Self {
        Self { height: 19, width: 1, frames: 400, patch_height: 1, patch_width: 1, tubelet: 10, ..Self::icub20() }
    }

    /// GelSight-style optical tactile video: 25 RGB frames of 240 × 320, patches 40 × 40.
    pub fn gelsight() -> Self {
        Self {
            height: 240,
            width: 320,
            channels: 3,
            frames: 25,
            patch_height: 40,
            patch_width: 40,
            dim: 64,
            mlp_dim: 128,
            ..Self::icub20()
        }
    }

    pub fn preset(name: &str) -> Result<Self> {
        match name {
            "icub20" => Ok(Self::icub20()),
            "biotac20" => Ok(Self::biotac20()),
            "gelsight" => Ok(Self::gelsight()),
            _ => Err(Error::UnknownPreset(name.to_string())),
        }
    }

    /// Checks that the sizes fit together.
    pub fn validate(&self) -> Result<()> {
        let positive = [
            ("height", self.height),
            ("width", self.width),
            ("channels", self.channels),
            ("frames", self.frames),
            ("patch_height", self.patch_height),
            ("patch_width", self.patch_width),
            ("tubelet", self.tubelet),
            ("dim", self.dim),
            ("heads", self.heads),
            ("dim_head", self.dim_head),
            ("mlp_dim", self.mlp_dim),
            ("classes", self.classes),
        ];
        if let Some((name, _)) = positive.iter().find(|(_, v)| *v == 0) {
            return Err(Error::Config(format!("{name} must be at least 1")));
        }
        let divides = [
            ("patch_height", self.patch_height, "height", self.height),
            ("patch_width", self.patch_width, "width", self.width),
            ("tubelet", self.tubelet, "frames", self.frames),
        ];
        for (pn, p, n, v) in divides {
            if v % p != 0 {
                return Err(Error::Config(format!("{pn} = {p} does not divide {n} = {v}")));
            }
        }
        if !(0.0..1.0).contains(&self.dropout) {
            return Err(Error::Config(format!("dropout = {} is not in [0, 1)", self.dropout)));
        }
        Ok(())
    }

    /// Spatial patches per temporal token.
    pub fn num_patches(&self) -> usize {
        (self.height / self.patch_height) * (self.width / self.patch_width)
    }

    /// Values in one patch token: tubelet × patch_height × patch_width × channels.
    pub fn patch_dim(&self) -> usize {
        self.tubelet * self.patch_height * self.patch_width * self.channels
    }

    /// Temporal tokens (= entries of the frame-selection mask).
    pub fn time_tokens(&self) -> usize {
        self.frames / self.tubelet
    }

    /// Width of the attention's q, k and v: heads × dim_head.
    pub fn inner_dim(&self) -> usize {
        self.heads * self.dim_head
    }

    /// The shape of one sample, without the batch dimension.
    pub fn sample_shape(&self) -> Vec<usize> {
        if self.channels == 1 {
            vec![self.height, self.width, self.frames]
        } else {
            vec![self.height, self.width, self.channels, self.frames]
        }
    }

    /// Trainable parameters of one transformer layer, channel masks included.
    fn layer_parameters(&self) -> usize {
        let (d, i, m) = (self.dim, self.inner_dim(), self.mlp_dim);
        let norms = 2 * 2 * d;
        let attn = d * 3 * i + i + i * d + d;
        let ffn = d * m + m + m + m * d + d;
        norms + attn + ffn
    }

    /// Trainable parameters, channel masks included, the frame-selection mask not.
    pub fn parameter_count(&self) -> usize {
        let d = self.dim;
        let embed = self.patch_dim() * d + d;
        let pos = self.time_tokens() * (self.num_patches() + 1) * d;
        let cls = 2 * d;
        let transformers = (self.space_depth + self.time_depth) * self.layer_parameters() + 2 * 2 * d;
        let head = 2 * d + d * self.classes + self.classes;
        embed + pos + cls + transformers + head
    }

    /// Multiply-adds of one transformer layer over `seqs` sequences of `len` tokens.
    fn layer_mult_adds(&self, seqs: usize, len: usize) -> u64 {
        let (d, i, m) = (self.dim, self.inner_dim(), self.mlp_dim);
        let per_token = d * 3 * i + i * d + 2 * d * m;
        let attention = 2 * len * len * i;
        (seqs * (len * per_token + attention)) as u64
    }

    /// Multiply-adds for one sample (matrix products only; norms, softmax and GELU are not
    /// counted).
    pub fn mult_adds(&self) -> u64 {
        let t = self.time_tokens();
        let n = self.num_patches();
        let embed = (t * n * self.patch_dim() * self.dim) as u64;
        let space = self.space_depth as u64 * self.layer_mult_adds(t, n + 1);
        let time = self.time_depth as u64 * self.layer_mult_adds(1, t + 1);
        embed + space + time + (self.dim * self.classes) as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn icub20_matches_the_published_parameter_count() {
        let cfg = Config::icub20();
        assert_eq!(cfg.num_patches(), 4);
        assert_eq!(cfg.patch_dim(), 15);
        assert_eq!(cfg.parameter_count(), 64_272);
    }

    #[test]
    fn presets_validate_and_round_trip_through_json() {
        for name in PRESETS {
            let cfg = Config::preset(name).unwrap();
            cfg.validate().unwrap();
            let back: Config = serde_json::from_str(&serde_json::to_string(&cfg).unwrap()).unwrap();
            assert_eq!(back, cfg);
        }
        assert!(matches!(Config::preset("nope"), Err(Error::UnknownPreset(_))));
    }

    #[test]
    fn validate_names_the_misfit() {
        let cfg = Config { patch_width: 3, ..Config::icub20() };
        let msg = cfg.validate().unwrap_err().to_string();
        assert!(msg.contains("patch_width = 3 does not divide width = 10"), "{msg}");
    }
}
