//! What only one network has: the sizes PVT³, ViT and RAEC do not share, one type each, so that
//! a configuration holds its own network's fields and no other's.
//!
//! Each field is declared once, in a [`network_fields!`] list: its doc, name, type, default and
//! when a configuration file writes it. The struct, its `Default` and its JSON form (the file's
//! fields, the foreign-field check, the names `--set` takes) all come from that one line, so a
//! new field is that line and the code that reads it (docs/architecture.md, "Adding a model
//! field").

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::{Error, Result};

/// When a configuration file writes a network's field.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Written {
    /// Always.
    Always,
    /// Only where it differs from its default, so that the files of models from before the
    /// field existed read as they did.
    Changed,
}

/// One of a network's fields as a configuration file holds it.
#[derive(Clone, Debug, PartialEq)]
pub struct Entry {
    pub name: &'static str,
    pub value: Value,
    /// Whether a file writes it ([`Written`]).
    pub written: bool,
}

/// A network's own fields, as [`network_fields!`] declares them.
pub trait NetworkFields: Sized {
    /// Every field as JSON, in the order of its declaration (which files keep).
    fn entries(&self) -> Vec<Entry>;

    /// The fields from a file's values (`value(name)`: the file's, if it holds the field and it
    /// is not null), the others at their defaults.
    fn from_values(value: impl Fn(&str) -> Option<Value>) -> Result<Self>;
}

/// A field's value read from a file, or its default where the file lacks it.
fn read_field<T: serde::de::DeserializeOwned>(name: &str, value: Option<Value>, default: T) -> Result<T> {
    match value {
        None => Ok(default),
        Some(v) => serde_json::from_value(v.clone()).map_err(|e| Error::Config(format!("{name} = {v}: {e}"))),
    }
}

/// Declares a network's fields once: `/// doc` lines, then `name: Type = default, written;`
/// (`always` or `changed`, see [`Written`]). Makes the struct, its `Default` and its
/// [`NetworkFields`].
macro_rules! network_fields {
    (
        $(#[$doc:meta])*
        $name:ident {
            $( $(#[$field_doc:meta])* $field:ident: $ty:ty = $default:expr, $written:ident; )*
        }
    ) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct $name {
            $( $(#[$field_doc])* pub $field: $ty, )*
        }

        impl Default for $name {
            fn default() -> Self {
                Self { $( $field: $default, )* }
            }
        }

        impl NetworkFields for $name {
            fn entries(&self) -> Vec<Entry> {
                let default = Self::default();
                vec![$(Entry {
                    name: stringify!($field),
                    value: serde_json::to_value(self.$field).expect("a number or a truth value"),
                    written: network_fields!(@$written) == Written::Always || self.$field != default.$field,
                }),*]
            }

            fn from_values(value: impl Fn(&str) -> Option<Value>) -> Result<Self> {
                let default = Self::default();
                Ok(Self { $( $field: read_field(stringify!($field), value(stringify!($field)), default.$field)?, )* })
            }
        }
    };
    (@always) => { Written::Always };
    (@changed) => { Written::Changed };
}

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
    /// The network's fields as JSON, in the order a file writes them.
    pub fn entries(&self) -> Vec<Entry> {
        match self {
            Self::Pvt3(p) => p.entries(),
            Self::Vit(v) => v.entries(),
            Self::Raec(r) => r.entries(),
        }
    }

    /// `architecture`'s network from a file's values (`value(name)`: the file's value of a field,
    /// if it holds one that is not null). A field of another network is refused, naming it,
    /// unless it holds that network's default (files from before configurations were split by
    /// network hold every network's fields).
    pub fn from_values(architecture: Architecture, value: impl Fn(&str) -> Option<Value>) -> Result<Self> {
        for other in Architecture::ALL.into_iter().filter(|a| *a != architecture) {
            for default in Self::new(other).entries() {
                match value(default.name) {
                    Some(v) if v != default.value => {
                        return Err(Error::Config(format!("{} = {v}: not a field of a {architecture} model", default.name)))
                    }
                    _ => {}
                }
            }
        }
        Ok(match architecture {
            Architecture::Pvt3 => Pvt3Config::from_values(value)?.into(),
            Architecture::Vit => VitConfig::from_values(value)?.into(),
            Architecture::Raec => RaecConfig::from_values(value)?.into(),
        })
    }

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

network_fields! {
    /// PVT³'s own fields.
    Pvt3Config {
        /// Frequency bands of the spectral head (`crate::spectrum`), which adds to the transformer's
        /// logits a linear map of each channel's mean level and log band powers over the kept frames
        /// received so far (the whole window at the end of a touch); 0 has no such head.
        spectral_bands: usize = 0, always;
        /// Whether the spectral head reads each channel's mean level beside its band powers. Off, it
        /// reads the band powers alone: what a texture makes the sensor vibrate, and not the press,
        /// which sets a capacitive channel's level, nor the sliding direction, which shifts it
        /// (docs/robustness.md); the transformer reads the levels all the same.
        spectral_levels: bool = true, changed;
        /// Whether the spectral head reads an image's space instead of each channel's frames: for
        /// each colour of each frame, its mean level and the mean power of `spectral_bands` rings of
        /// spatial frequency (`crate::spectrum::space`), averaged over the kept frames received so
        /// far. A texture's spectrum stays where the imprint moves, so it reads a camera's texture
        /// wherever the gel is pressed (docs/camera.md).
        spectral_space: bool = false, changed;
        /// Bins of a histogram of each colour's normalised pixel values, read by a head over the
        /// image's space beside the rings (`crate::spectrum::space::histogram_matrix`): how much of
        /// the gel a touch presses and how far, which a spectrum does not say; 0 has none. Soft bins
        /// (each value shared linearly between the two nearest bins' centres) over
        /// `[-HISTOGRAM_RANGE, HISTOGRAM_RANGE]`, the outer two holding the tails.
        spectral_histogram: usize = 0, changed;
        /// Whether a head with a histogram also reads, with the same bins, histograms of each colour's
        /// differences between neighbouring normalised pixels, across and down
        /// (`crate::spectrum::space::Histogram`): how steep the imprint's slopes are and which way they
        /// face, wherever it lies, which neither the values' histogram nor the rings' powers say.
        spectral_gradients: bool = false, changed;
        /// Whether a head over the image's space reads a touch as the mean of its frames' features,
        /// the logarithm taken of each frame's ring powers, instead of the logarithm of their mean
        /// power. The fit reads every frame as a row (docs/camera.md, "Every frame a row"), so the
        /// touch is then read in the units it was fitted in. The levels and histograms are means
        /// either way.
        spectral_log_frames: bool = false, changed;
        /// Whether a head over the image's space also reads each colour's pixels, averaged over the
        /// frames as the levels are: where on the gel a touch presses, the imprint of a shape or of
        /// a still material, which rings and histograms discard. The fit chooses on the validation
        /// fold whether the head reads the texture's features, the pixels or both
        /// (`pvt3_trainer`'s `spectrum_fit`; docs/camera.md, "Where the gel is pressed").
        spectral_pixels: bool = false, changed;
        /// A patch-selection mask (`patch_mask`, one entry per patch of the grid, starting at one)
        /// scales each patch's embeddings, as the frame mask scales a temporal token's; a patch whose
        /// entry is zero is dropped from the spatial sequence, so pruning it removes its token and
        /// the runtime never embeds its pixels. Off, the model has no such mask.
        patch_selection: bool = false, changed;
        /// Patch dropout (PatchDropout, Liu et al. 2022): at each training step every patch of the
        /// grid that the patch mask keeps is dropped from the spatial sequence with this probability
        /// (one patch kept at least), the same patches for the whole batch. A model that learns to
        /// answer from any part of the image loses less when patch selection prunes some. Evaluation
        /// and every exported form read all patches. 0: off.
        patch_dropout: f64 = 0.0, changed;
    }
}

network_fields! {
    /// ViT's own fields.
    VitConfig {
        /// The frames are tiled row-major into one large frame `tile_rows` frames high.
        tile_rows: usize = 1, always;
    }
}

network_fields! {
    /// RAEC's own fields. Its convolution's kernel is the configuration's patch, and it reads
    /// `tubelet` frames per step.
    RaecConfig {
        /// Hidden width of the LSTM encoder and decoder.
        rnn_hidden: usize = 90, always;
        /// Width of the latent code the classifier reads.
        latent: usize = 40, always;
        /// Output channels of the convolution (kernel patch_height × patch_width, then 2 × 2
        /// max-pooling) in front of the encoder; 0 feeds the frames to the LSTM as they are.
        conv_channels: usize = 0, always;
        /// Weight of the reconstruction error (mean squared, on normalised frames) in the loss.
        reconstruction_weight: f64 = 0.01, always;
        /// The decoder as Gao et al. published it (their `vrae.py`): its LSTM reads zeros at every
        /// step and starts from a hidden state that is a linear map of the latent code. Off, it reads
        /// the code at every step from the zero state.
        decoder_from_state: bool = false, always;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Config;

    /// A value of `v`'s type other than `v`: what a user would set a field to.
    fn other(v: &Value) -> Value {
        match v {
            Value::Bool(b) => (!b).into(),
            Value::Number(n) if n.is_u64() => (n.as_u64().unwrap() + 3).into(),
            Value::Number(n) => (n.as_f64().unwrap() * 0.5 + 0.125).into(),
            _ => unreachable!("a field is a number or a truth value"),
        }
    }

    /// Whatever a `network_fields!` list declares is written to a file when set, read back from
    /// it, and refused by name in another network's file: a new field needs no edit here.
    #[test]
    fn every_declared_field_round_trips_through_a_file_and_is_foreign_elsewhere() {
        for architecture in Architecture::ALL {
            let defaults = Network::new(architecture).entries();
            assert!(!defaults.is_empty());
            for field in &defaults {
                let set = other(&field.value);
                let value = |name: &str| (name == field.name).then(|| set.clone());
                let network = Network::from_values(architecture, value).unwrap();
                let entry = network.entries().into_iter().find(|e| e.name == field.name).unwrap();
                assert_eq!((entry.value.clone(), entry.written), (set.clone(), true), "{architecture} {}", field.name);
                let cfg = Config { network: network.clone(), ..Config::icub20() };
                let file = serde_json::to_value(&cfg).unwrap();
                assert_eq!(file[field.name], set, "{architecture} {}: written", field.name);
                assert_eq!(serde_json::from_value::<Config>(file).unwrap().network, network, "{architecture} {}: read", field.name);
                for elsewhere in Architecture::ALL.into_iter().filter(|a| *a != architecture) {
                    let msg = Network::from_values(elsewhere, value).unwrap_err().to_string();
                    assert!(msg.contains(&format!("{} = {set}: not a field of a {elsewhere} model", field.name)), "{msg}");
                }
            }
        }
    }
}
