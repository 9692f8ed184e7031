//! What only one network has: the sizes PVT³, ViT and RAEC do not share, one type each, so that
//! a configuration holds its own network's fields and no other's.

use serde::{Deserialize, Serialize};

use crate::{Error, Result};

/// The network a configuration describes, by name.
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

/// The network and its own fields.
#[derive(Clone, Debug, PartialEq)]
pub enum Network {
    Pvt3(Pvt3Config),
    Vit(VitConfig),
    Raec(RaecConfig),
}

impl Network {
    /// `architecture`'s network with its default fields.
    pub fn new(architecture: Architecture) -> Self {
        match architecture {
            Architecture::Pvt3 => Pvt3Config::default().into(),
            Architecture::Vit => VitConfig::default().into(),
            Architecture::Raec => RaecConfig::default().into(),
        }
    }

    pub fn architecture(&self) -> Architecture {
        match self {
            Self::Pvt3(_) => Architecture::Pvt3,
            Self::Vit(_) => Architecture::Vit,
            Self::Raec(_) => Architecture::Raec,
        }
    }
}

/// PVT³'s own fields.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pvt3Config {
    /// Frequency bands of the spectral head (`crate::spectrum`), which adds to the transformer's
    /// logits a linear map of each channel's mean level and log band powers over the kept frames
    /// received so far (the whole window at the end of a touch); 0 has no such head.
    pub spectral_bands: usize,
    /// Whether the spectral head reads each channel's mean level beside its band powers. Off, it
    /// reads the band powers alone: what a texture makes the sensor vibrate, and not the press,
    /// which sets a capacitive channel's level, nor the sliding direction, which shifts it
    /// (docs/robustness.md); the transformer reads the levels all the same.
    pub spectral_levels: bool,
    /// Whether the spectral head reads an image's space instead of each channel's frames: for
    /// each colour of each frame, its mean level and the mean power of `spectral_bands` rings of
    /// spatial frequency (`crate::spectrum::space`), averaged over the kept frames received so
    /// far. A texture's spectrum stays where the imprint moves, so it reads a camera's texture
    /// wherever the gel is pressed (docs/camera.md).
    pub spectral_space: bool,
    /// Bins of a histogram of each colour's normalised pixel values, read by a head over the
    /// image's space beside the rings (`crate::spectrum::space::histogram_matrix`): how much of
    /// the gel a touch presses and how far, which a spectrum does not say; 0 has none. Soft bins
    /// (each value shared linearly between the two nearest bins' centres) over
    /// `[-HISTOGRAM_RANGE, HISTOGRAM_RANGE]`, the outer two holding the tails.
    pub spectral_histogram: usize,
    /// Whether a head with a histogram also reads, with the same bins, histograms of each colour's
    /// differences between neighbouring normalised pixels, across and down
    /// (`crate::spectrum::space::Histogram`): how steep the imprint's slopes are and which way they
    /// face, wherever it lies, which neither the values' histogram nor the rings' powers say.
    pub spectral_gradients: bool,
    /// Whether a head over the image's space reads a touch as the mean of its frames' features,
    /// the logarithm taken of each frame's ring powers, instead of the logarithm of their mean
    /// power. The fit reads every frame as a row (docs/camera.md, "Every frame a row"), so the
    /// touch is then read in the units it was fitted in. The levels and histograms are means
    /// either way.
    pub spectral_log_frames: bool,
    /// A patch-selection mask (`patch_mask`, one entry per patch of the grid, starting at one)
    /// scales each patch's embeddings, as the frame mask scales a temporal token's; a patch whose
    /// entry is zero is dropped from the spatial sequence, so pruning it removes its token and
    /// the runtime never embeds its pixels. Off, the model has no such mask.
    pub patch_selection: bool,
    /// Patch dropout (PatchDropout, Liu et al. 2022): at each training step every patch of the
    /// grid that the patch mask keeps is dropped from the spatial sequence with this probability
    /// (one patch kept at least), the same patches for the whole batch. A model that learns to
    /// answer from any part of the image loses less when patch selection prunes some. Evaluation
    /// and every exported form read all patches. 0: off.
    pub patch_dropout: f64,
}

impl Default for Pvt3Config {
    fn default() -> Self {
        Self {
            spectral_bands: 0,
            spectral_levels: true,
            spectral_space: false,
            spectral_histogram: 0,
            spectral_gradients: false,
            spectral_log_frames: false,
            patch_selection: false,
            patch_dropout: 0.0,
        }
    }
}

/// ViT's own fields.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VitConfig {
    /// The frames are tiled row-major into one large frame `tile_rows` frames high.
    pub tile_rows: usize,
}

impl Default for VitConfig {
    fn default() -> Self {
        Self { tile_rows: 1 }
    }
}

/// RAEC's own fields. Its convolution's kernel is the configuration's patch, and it reads
/// `tubelet` frames per step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RaecConfig {
    /// Hidden width of the LSTM encoder and decoder.
    pub rnn_hidden: usize,
    /// Width of the latent code the classifier reads.
    pub latent: usize,
    /// Output channels of the convolution (kernel patch_height × patch_width, then 2 × 2
    /// max-pooling) in front of the encoder; 0 feeds the frames to the LSTM as they are.
    pub conv_channels: usize,
    /// Weight of the reconstruction error (mean squared, on normalised frames) in the loss.
    pub reconstruction_weight: f64,
    /// The decoder as Gao et al. published it (their `vrae.py`): its LSTM reads zeros at every
    /// step and starts from a hidden state that is a linear map of the latent code. Off, it reads
    /// the code at every step from the zero state.
    pub decoder_from_state: bool,
}

impl Default for RaecConfig {
    fn default() -> Self {
        Self { rnn_hidden: 90, latent: 40, conv_channels: 0, reconstruction_weight: 0.01, decoder_from_state: false }
    }
}

impl RaecConfig {
    /// Whether the decoder mirrors the convolution (Gao et al.'s iCub decoder: un-pooling, then
    /// a transposed convolution), which it does for the published decoder of a model with one.
    pub fn decoder_mirrors_conv(&self) -> bool {
        self.decoder_from_state && self.conv_channels > 0
    }

    /// Rows and columns of the convolution's output (before pooling) on `cfg`'s frames.
    pub fn conv_output(&self, cfg: &super::Config) -> (usize, usize) {
        ((cfg.height + 1).saturating_sub(cfg.patch_height), (cfg.width + 1).saturating_sub(cfg.patch_width))
    }

    /// The width of one step of the encoder's input sequence (the pooled convolution's output,
    /// or the step's raw frames).
    pub fn rnn_input(&self, cfg: &super::Config) -> usize {
        if self.conv_channels == 0 {
            return cfg.step_values();
        }
        let (h, w) = self.conv_output(cfg);
        self.conv_channels * (h / 2) * (w / 2)
    }

    /// The width of the decoder's linear output per step: the pooled convolution's output when
    /// the decoder mirrors the convolution, the step's raw frames otherwise.
    pub fn decoder_output(&self, cfg: &super::Config) -> usize {
        if self.decoder_mirrors_conv() {
            self.rnn_input(cfg)
        } else {
            cfg.step_values()
        }
    }
}

impl From<Pvt3Config> for Network {
    fn from(c: Pvt3Config) -> Self {
        Self::Pvt3(c)
    }
}

impl From<VitConfig> for Network {
    fn from(c: VitConfig) -> Self {
        Self::Vit(c)
    }
}

impl From<RaecConfig> for Network {
    fn from(c: RaecConfig) -> Self {
        Self::Raec(c)
    }
}
