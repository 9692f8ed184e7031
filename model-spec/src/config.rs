//! The model configuration, with named presets for the supported sensors.
//!
//! Every size is configurable. Inputs are `[batch, height, width, frames]` for single-channel
//! sensors and `[batch, height, width, channels, frames]` otherwise. A temporal patch (`tubelet`)
//! groups consecutive frames into one token, so that long recordings train in reasonable time;
//! the frame-selection mask then has one entry per tubelet.
//!
//! The same configuration describes the paper's two baselines (`model: vit` or `raec`), so that
//! one trainer, one checkpoint format and one `pvt3 info` serve all three; each sensor preset has
//! a `vit-` and a `raec-` variant.

use serde::{Deserialize, Serialize};

use crate::{Error, Result};

/// The sensor presets (PVT³); each also comes as `vit-NAME` and `raec-NAME`.
pub const PRESETS: [&str; 3] = ["icub20", "biotac20", "gelsight"];

/// The network a configuration describes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Architecture {
    /// PVT³: the ViViT factorised encoder with channel- and frame-selection masks.
    #[default]
    Pvt3,
    /// The paper's ViT: all frames tiled into one large frame, one transformer over its patches.
    Vit,
    /// The recurrent autoencoder classifier of Gao et al. (IROS 2020).
    Raec,
}

impl Architecture {
    pub const ALL: [Self; 3] = [Self::Pvt3, Self::Vit, Self::Raec];

    pub fn name(self) -> &'static str {
        match self {
            Self::Pvt3 => "pvt3",
            Self::Vit => "vit",
            Self::Raec => "raec",
        }
    }
}

impl std::fmt::Display for Architecture {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Architecture {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        Self::ALL
            .into_iter()
            .find(|a| a.name() == s)
            .ok_or_else(|| Error::Config(format!("unknown model `{s}`; expected pvt3, vit or raec")))
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Config {
    /// The network: `pvt3`, `vit` or `raec`.
    #[serde(default)]
    pub model: Architecture,
    /// Sensor grid rows (taxels or electrodes).
    pub height: usize,
    /// Sensor grid columns.
    pub width: usize,
    /// Values per taxel and frame (3 for RGB).
    pub channels: usize,
    /// Frames in one input window.
    pub frames: usize,
    /// Patch rows (PVT³: of a frame; ViT: of the tiled frame; RAEC: the convolution kernel's).
    pub patch_height: usize,
    /// Patch columns (as `patch_height`).
    pub patch_width: usize,
    /// Frames per temporal token.
    pub tubelet: usize,
    /// Embedding width.
    pub dim: usize,
    /// Layers of the spatial transformer (ViT: its one transformer has both depths' layers).
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
    /// ViT: the frames are tiled row-major into one large frame `tile_rows` frames high.
    #[serde(default = "one")]
    pub tile_rows: usize,
    /// RAEC: hidden width of the LSTM encoder and decoder.
    #[serde(default = "default_rnn_hidden")]
    pub rnn_hidden: usize,
    /// RAEC: width of the latent code the classifier reads.
    #[serde(default = "default_latent")]
    pub latent: usize,
    /// RAEC: output channels of the convolution (kernel patch_height × patch_width, then 2 × 2
    /// max-pooling) in front of the encoder; 0 feeds the frames to the LSTM as they are.
    #[serde(default)]
    pub conv_channels: usize,
    /// RAEC: weight of the reconstruction error (mean squared, on normalised frames) in the loss.
    #[serde(default = "default_reconstruction_weight")]
    pub reconstruction_weight: f64,
    /// RAEC: the decoder as Gao et al. published it (their `vrae.py`): its LSTM reads zeros at
    /// every step and starts from a hidden state that is a linear map of the latent code. Off
    /// (the default), it reads the code at every step from the zero state. Written only when
    /// on, so that every other model's files (and their digests) are as before.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub decoder_from_state: bool,
    /// PVT³: frequency bands of the spectral head (`crate::spectrum`), which adds to the
    /// transformer's logits a linear map of each channel's mean level and log band powers over
    /// the window; 0 (the default) has no such head. Written only when set, as
    /// `decoder_from_state`.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub spectral_bands: usize,
}

fn is_zero(v: &usize) -> bool {
    *v == 0
}

/// The frequencies of a real transform of `frames` values, 0 to `frames / 2`: what the spectral
/// head (`crate::spectrum`) reads of each channel.
pub fn spectral_bins(frames: usize) -> usize {
    frames / 2 + 1
}

fn default_eps() -> f64 {
    1e-5
}

fn one() -> usize {
    1
}

fn default_rnn_hidden() -> usize {
    90
}

fn default_latent() -> usize {
    40
}

fn default_reconstruction_weight() -> f64 {
    0.01
}

impl Config {
    /// The fields written only when they differ from their default (`skip_serializing_if`), so
    /// absent from a configuration's JSON otherwise.
    pub const OPTIONAL_FIELDS: &[&str] = &["decoder_from_state", "spectral_bands"];

    /// The iCub forearm skin preset of DESIGN.md: 6 × 10 taxels, 75 frames, 20 classes,
    /// exactly 64,272 trainable parameters besides the frame mask.
    pub fn icub20() -> Self {
        Self {
            model: Architecture::Pvt3,
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
            tile_rows: 1,
            rnn_hidden: default_rnn_hidden(),
            latent: default_latent(),
            conv_channels: 0,
            reconstruction_weight: default_reconstruction_weight(),
            decoder_from_state: false,
            spectral_bands: 0,
        }
    }

    /// BioTac: 19 electrodes with no regular grid, 400 frames. The 19 electrodes of 10
    /// consecutive frames form one token (a 19 × 1 grid cut as one 19 × 1 patch, tubelet 10):
    /// 40 temporal tokens, each a single spatial patch with its CLS token. Tokens of one
    /// electrode each (patch 1 × 1) let the model fit per-electrode levels and overfit: 0.9113
    /// against 0.97 in cross-validation (docs/results.md).
    pub fn biotac20() -> Self {
        Self { height: 19, width: 1, frames: 400, patch_height: 19, patch_width: 1, tubelet: 10, ..Self::icub20() }
    }

    /// A sensor no preset fits, samples `[height, width, (channels,) frames]`: the BioTac layout,
    /// which assumes no grid. All channels of a tubelet form one token (one patch covering the
    /// frame), and the tubelet is the divisor of `frames` nearest (in ratio) to `frames / 40`, so
    /// that about 40 temporal tokens remain, as in the BioTac preset. The rest is the BioTac
    /// preset's. `None` for a shape that is not 3 or 4 axes of positive lengths.
    pub fn for_sensor(sample_shape: &[usize]) -> Option<Self> {
        let (height, width, channels, frames) = match *sample_shape {
            [h, w, f] => (h, w, 1, f),
            [h, w, c, f] => (h, w, c, f),
            _ => return None,
        };
        if [height, width, channels, frames].contains(&0) {
            return None;
        }
        let ideal = frames as f64 / 40.0;
        let distance = |d: usize| (d as f64 / ideal).ln().abs();
        let tubelet = (1..=frames).filter(|d| frames.is_multiple_of(*d)).min_by(|a, b| distance(*a).total_cmp(&distance(*b)))?;
        Some(Self { height, width, channels, frames, patch_height: height, patch_width: width, tubelet, ..Self::biotac20() })
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

    /// A sensor preset (`icub20`, `biotac20`, `gelsight`), optionally prefixed `vit-` or `raec-`.
    pub fn preset(name: &str) -> Result<Self> {
        let (model, sensor) = match name.split_once('-') {
            Some(("vit", sensor)) => (Architecture::Vit, sensor),
            Some(("raec", sensor)) => (Architecture::Raec, sensor),
            _ => (Architecture::Pvt3, name),
        };
        let cfg = match sensor {
            "icub20" => Self::icub20(),
            "biotac20" => Self::biotac20(),
            "gelsight" => Self::gelsight(),
            _ => return Err(Error::UnknownPreset(name.to_string())),
        };
        Ok(cfg.for_model(model))
    }

    /// The baseline `model` for this configuration's sensor, with its preset sizes.
    ///
    /// ViT keeps the embedding, heads and all eight layers of the ViViT backbone (so it has about
    /// its parameter count) and takes patches of the tiled frame that never straddle two frames:
    /// half an iCub frame (6 × 5, 150 tokens), all 19 BioTac electrodes × 10 frames (40 tokens),
    /// a GelSight frame's own 40 × 40 patches. RAEC takes Gao et al.'s sizes: a 3-channel 3 × 5
    /// convolution for grids big enough for it, the raw frames otherwise, read in steps of the
    /// PVT³ preset's tubelet (BioTac: 40 steps of 10 frames; 400 single-frame steps trained 18×
    /// slower, 0.9 s against 0.05 s per batch of 32).
    pub fn for_model(self, model: Architecture) -> Self {
        match model {
            Architecture::Pvt3 => Self { model, ..self },
            Architecture::Vit => {
                let (patch_height, patch_width, tile_rows) = match (self.height, self.width) {
                    (h, 1) => (h, self.tubelet, 1),
                    (h, w) if h * w <= 64 => (h, w / 2, 5.min(self.frames)),
                    _ => (self.patch_height, self.patch_width, 1),
                };
                Self { model, patch_height, patch_width, tile_rows, tubelet: 1, ..self }
            }
            Architecture::Raec => {
                let conv = self.height >= 3 && self.width >= 5;
                let (patch_height, patch_width) = if conv { (3, 5) } else { (1, 1) };
                let (conv_channels, tubelet) = if conv { (3, 1) } else { (0, self.tubelet) };
                Self { model, patch_height, patch_width, conv_channels, tubelet, ..self }
            }
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
            ("tile_rows", self.tile_rows),
            ("rnn_hidden", self.rnn_hidden),
            ("latent", self.latent),
        ];
        if let Some((name, _)) = positive.iter().find(|(_, v)| *v == 0) {
            return Err(Error::Config(format!("{name} must be at least 1")));
        }
        if !(0.0..1.0).contains(&self.dropout) {
            return Err(Error::Config(format!("dropout = {} is not in [0, 1)", self.dropout)));
        }
        if self.tubelet != 1 && (self.model == Architecture::Vit || self.conv_channels > 0) {
            return Err(Error::Config(format!(
                "tubelet = {} needs a model that reads frames in groups: PVT³, or RAEC without convolution",
                self.tubelet
            )));
        }
        let divides = match self.model {
            Architecture::Pvt3 => vec![
                ("patch_height", self.patch_height, "height", self.height),
                ("patch_width", self.patch_width, "width", self.width),
                ("tubelet", self.tubelet, "frames", self.frames),
            ],
            Architecture::Vit => {
                let (th, tw) = self.tiled_size();
                vec![
                    ("tile_rows", self.tile_rows, "frames", self.frames),
                    ("patch_height", self.patch_height, "the tiled frame's height", th),
                    ("patch_width", self.patch_width, "the tiled frame's width", tw),
                ]
            }
            Architecture::Raec => {
                if self.conv_channels > 0 && (self.conv_output().0 < 2 || self.conv_output().1 < 2) {
                    return Err(Error::Config(format!(
                        "a {} × {} convolution and 2 × 2 pooling do not fit a {} × {} frame",
                        self.patch_height, self.patch_width, self.height, self.width
                    )));
                }
                let (ch, cw) = self.conv_output();
                if self.decoder_mirrors_conv() && (ch % 2 != 0 || cw % 2 != 0) {
                    return Err(Error::Config(format!(
                        "decoder_from_state un-pools the {ch} × {cw} convolution output, which 2 × 2 pooling must tile"
                    )));
                }
                vec![("tubelet", self.tubelet, "frames", self.frames)]
            }
        };
        if self.spectral_bands > 0 {
            self.require_pvt3("spectral_bands")?;
            if self.spectral_bands > self.frames / 2 {
                return Err(Error::Config(format!(
                    "spectral_bands = {} is more than the {} frequencies above 0 of {} frames",
                    self.spectral_bands,
                    self.frames / 2,
                    self.frames
                )));
            }
        }
        for (pn, p, n, v) in divides {
            if v % p != 0 {
                return Err(Error::Config(format!("{pn} = {p} does not divide {n} = {v}")));
            }
        }
        Ok(())
    }

    /// Fails, naming `what`, unless this configuration is PVT³'s.
    pub fn require_pvt3(&self, what: &str) -> Result<()> {
        if self.model == Architecture::Pvt3 {
            return Ok(());
        }
        Err(Error::Config(format!("{what}: PVT³ models only, and this is a {} model", self.model)))
    }

    /// Whether the model answers from a part of a window: streamed frame by frame, provisional
    /// answers, a stopping rule. Not with a spectral head, whose features are the whole
    /// window's. (The runtime reads the same from a file: its `spectral_logits` seam.)
    pub fn streams(&self) -> bool {
        self.spectral_bands == 0
    }

    /// Fails, naming `what`, if the model does not [`Self::streams`].
    pub fn require_streams(&self, what: &str) -> Result<()> {
        if self.streams() {
            return Ok(());
        }
        Err(Error::Config(format!(
            "{what}: a model with a spectral head (spectral_bands = {}) reads the whole window",
            self.spectral_bands
        )))
    }

    /// ViT: rows and columns of the frame all frames are tiled into.
    pub fn tiled_size(&self) -> (usize, usize) {
        (self.height * self.tile_rows, self.width * self.frames.div_ceil(self.tile_rows))
    }

    /// RAEC: rows and columns of the convolution's output (before pooling).
    fn conv_output(&self) -> (usize, usize) {
        ((self.height + 1).saturating_sub(self.patch_height), (self.width + 1).saturating_sub(self.patch_width))
    }

    /// RAEC: the values of one step (`tubelet` raw frames) that the decoder reconstructs.
    pub fn step_values(&self) -> usize {
        self.tubelet * self.height * self.width * self.channels
    }

    /// RAEC: whether the decoder mirrors the convolution (Gao et al.'s iCub decoder: un-pooling,
    /// then a transposed convolution), which it does for the published decoder of a model with one.
    pub fn decoder_mirrors_conv(&self) -> bool {
        self.decoder_from_state && self.conv_channels > 0
    }

    /// RAEC: the width of the decoder's linear output per step: the pooled convolution's output
    /// when the decoder mirrors the convolution, the step's raw frames otherwise.
    pub fn decoder_output(&self) -> usize {
        if self.decoder_mirrors_conv() {
            self.rnn_input()
        } else {
            self.step_values()
        }
    }

    /// RAEC: the width of one step of the encoder's input sequence (the pooled convolution's
    /// output, or the step's raw frames).
    pub fn rnn_input(&self) -> usize {
        if self.conv_channels == 0 {
            return self.step_values();
        }
        let (h, w) = self.conv_output();
        self.conv_channels * (h / 2) * (w / 2)
    }

    /// Spatial patches per temporal token (ViT: patches of the tiled frame).
    pub fn num_patches(&self) -> usize {
        let (h, w) = if self.model == Architecture::Vit { self.tiled_size() } else { (self.height, self.width) };
        (h / self.patch_height) * (w / self.patch_width)
    }

    /// Values in one patch token: tubelet × patch_height × patch_width × channels.
    pub fn patch_dim(&self) -> usize {
        self.tubelet * self.patch_height * self.patch_width * self.channels
    }

    /// Temporal tokens (= entries of the frame-selection mask).
    pub fn time_tokens(&self) -> usize {
        self.frames / self.tubelet
    }

    /// Checks that `tokens` temporal tokens are a prefix of a window: 1 to all of them.
    pub fn check_prefix(&self, tokens: usize) -> Result<()> {
        let t = self.time_tokens();
        if tokens == 0 || tokens > t {
            return Err(Error::InputShape { got: vec![tokens], expected: format!("1 to {t} temporal tokens") });
        }
        Ok(())
    }

    /// Width of the attention's q, k and v: heads × dim_head.
    pub fn inner_dim(&self) -> usize {
        self.heads * self.dim_head
    }

    /// Checks that `dims` are those of a batch of samples of [`Self::sample_shape`]; returns the
    /// batch size.
    pub fn check_input(&self, dims: &[usize]) -> Result<usize> {
        let expected = self.sample_shape();
        if dims.len() != expected.len() + 1 || dims[1..] != expected[..] {
            let expected = expected.iter().map(|v| v.to_string()).collect::<Vec<_>>().join(", ");
            return Err(Error::InputShape { got: dims.to_vec(), expected });
        }
        Ok(dims[0])
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
        let (d, n, c) = (self.dim, self.num_patches(), self.classes);
        let head = 2 * d + d * c + c;
        match self.model {
            Architecture::Pvt3 => {
                let embed = self.patch_dim() * d + d;
                let pos = self.time_tokens() * (n + 1) * d;
                let transformers = (self.space_depth + self.time_depth) * self.layer_parameters() + 2 * 2 * d;
                embed + pos + 2 * d + transformers + head + self.spectral_parameters()
            }
            Architecture::Vit => {
                let embed = self.patch_dim() * d + d;
                let transformer = (self.space_depth + self.time_depth) * self.layer_parameters() + 2 * d;
                embed + (n + 1) * d + d + transformer + head
            }
            Architecture::Raec => {
                let (h, l) = (self.rnn_hidden, self.latent);
                let lstm = |input: usize| 4 * h * (input + h) + 2 * 4 * h;
                let conv = self.conv_channels * (self.patch_height * self.patch_width * self.channels + 1);
                let out = self.decoder_output();
                // The published decoder: an LSTM of one (zero) input, its state mapped from the
                // code; with a convolution, a transposed one mirrors it.
                let decoder = if self.decoder_from_state { lstm(1) + (l * h + h) } else { lstm(l) };
                let deconv = if self.decoder_mirrors_conv() {
                    self.conv_channels * self.channels * self.patch_height * self.patch_width + self.channels
                } else {
                    0
                };
                conv + lstm(self.rnn_input()) + (h * l + l) + (l * c + c) + decoder + (h * out + out) + deconv
            }
        }
    }

    /// PVT³: the sensor channels of a window (taxels or electrodes, times colours), the rows
    /// the spectral head reads.
    pub fn sensor_channels(&self) -> usize {
        self.height * self.width * self.channels
    }

    /// PVT³: the spectral head's features, a level and `spectral_bands` log powers per channel
    /// (0 without the head).
    pub fn spectral_features(&self) -> usize {
        if self.spectral_bands == 0 {
            0
        } else {
            self.sensor_channels() * (1 + self.spectral_bands)
        }
    }

    /// The spectral head's parameters: a scale and a shift per feature, and the linear map.
    fn spectral_parameters(&self) -> usize {
        let f = self.spectral_features();
        if f == 0 {
            0
        } else {
            2 * f + f * self.classes + self.classes
        }
    }

    /// The spectral head's multiply-adds as the exported graph computes them: per channel a
    /// Fourier transform of the frames (counted as a radix-2 FFT's `2 T log2 T`), the band sums of
    /// the squared transform, then the linear map.
    pub fn spectral_mult_adds(&self) -> u64 {
        if self.spectral_bands == 0 {
            return 0;
        }
        let t = self.frames as f64;
        let fft = (2.0 * t * t.log2()).ceil() as u64;
        let bands = (2 * spectral_bins(self.frames) * self.spectral_bands) as u64;
        self.sensor_channels() as u64 * (fft + bands) + (self.spectral_features() * self.classes) as u64
    }

    /// Multiply-adds of one transformer layer over `seqs` sequences of `len` tokens.
    fn layer_mult_adds(&self, seqs: usize, len: usize) -> u64 {
        let (d, i, m) = (self.dim, self.inner_dim(), self.mlp_dim);
        let per_token = d * 3 * i + i * d + 2 * d * m;
        let attention = 2 * len * len * i;
        (seqs * (len * per_token + attention)) as u64
    }

    /// Multiply-adds for one sample (matrix products and convolutions only; norms, softmax,
    /// activations and gates are not counted).
    pub fn mult_adds(&self) -> u64 {
        let (n, d, c) = (self.num_patches(), self.dim, self.classes);
        let head = (d * c) as u64;
        match self.model {
            Architecture::Pvt3 => {
                let t = self.time_tokens();
                let embed = (t * n * self.patch_dim() * d) as u64;
                let space = self.space_depth as u64 * self.layer_mult_adds(t, n + 1);
                let time = self.time_depth as u64 * self.layer_mult_adds(1, t + 1);
                embed + space + time + head + self.spectral_mult_adds()
            }
            Architecture::Vit => {
                let embed = (n * self.patch_dim() * d) as u64;
                embed + (self.space_depth + self.time_depth) as u64 * self.layer_mult_adds(1, n + 1) + head
            }
            Architecture::Raec => {
                let (h, l, t) = (self.rnn_hidden, self.latent, self.time_tokens());
                let (ch, cw) = self.conv_output();
                let conv = if self.conv_channels == 0 { 0 } else { ch * cw * self.conv_channels * self.patch_height * self.patch_width };
                let lstm = |input: usize| 4 * h * (input + h);
                // The decoder's input is the same at every step (the latent code, projected once)
                // or zeros (the published decoder, whose state is mapped from the code once).
                // A transposed convolution costs what the convolution it mirrors does.
                let deconv = if self.decoder_mirrors_conv() { conv * self.channels } else { 0 };
                let per_step = conv * self.channels + lstm(self.rnn_input()) + 4 * h * h + h * self.decoder_output() + deconv;
                let decoder_once = if self.decoder_from_state { h * l } else { 4 * h * l };
                (t * per_step + decoder_once + h * l + l * c) as u64
            }
        }
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

    /// A sensor without a preset gets the BioTac layout with about 40 temporal tokens, and the
    /// configuration validates and fits its samples.
    #[test]
    fn a_new_sensor_gets_the_biotac_layout() {
        for (shape, tubelet) in [(vec![24, 1, 250], 5), (vec![19, 1, 400], 10), (vec![4, 4, 3, 64], 2), (vec![8, 8, 37], 1)] {
            let cfg = Config::for_sensor(&shape).unwrap();
            cfg.validate().unwrap();
            assert_eq!((cfg.sample_shape(), cfg.tubelet, cfg.num_patches()), (shape.clone(), tubelet, 1), "{shape:?}");
        }
        assert_eq!(Config::for_sensor(&[19, 1, 400]).unwrap(), Config::biotac20());
        assert!(Config::for_sensor(&[10, 75]).is_none() && Config::for_sensor(&[0, 1, 4]).is_none());
    }

    #[test]
    fn validate_names_the_misfit() {
        let cfg = Config { patch_width: 3, ..Config::icub20() };
        let msg = cfg.validate().unwrap_err().to_string();
        assert!(msg.contains("patch_width = 3 does not divide width = 10"), "{msg}");
    }
}
