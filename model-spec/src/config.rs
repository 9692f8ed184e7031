//! The model configuration: the sensor's window, the tokens cut from it, the transformer's sizes
//! (shared by PVT³ and the paper's ViT), and the [`Network`] with the fields only it has.
//!
//! Every size is configurable. Inputs are `[batch, height, width, frames]` for single-channel
//! sensors and `[batch, height, width, channels, frames]` otherwise. A temporal patch (`tubelet`)
//! groups consecutive frames into one token, so that long recordings train in reasonable time;
//! the frame-selection mask then has one entry per tubelet. One trainer, one checkpoint format
//! and one `pvt3 info` serve all three networks; each sensor preset ([`presets`]) has a `vit-`
//! and a `raec-` variant. What a configuration costs is [`cost`]'s; its JSON form is [`file`]'s.

pub mod cost;
mod file;
pub mod network;
pub mod presets;

use serde::{Deserialize, Serialize};

pub use network::{Architecture, Network, Pvt3Config, RaecConfig, VitConfig};
pub use presets::PRESETS;

use crate::{Error, Result};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "file::ConfigFile", into = "file::ConfigFile")]
pub struct Config {
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
    /// Frames per temporal token (RAEC: per step of its LSTM).
    pub tubelet: usize,
    /// Embedding width (PVT³ and ViT).
    pub dim: usize,
    /// Layers of the spatial transformer (ViT: its one transformer has both depths' layers).
    pub space_depth: usize,
    pub time_depth: usize,
    pub heads: usize,
    pub dim_head: usize,
    /// Feed-forward hidden width.
    pub mlp_dim: usize,
    pub classes: usize,
    /// Dropout probability while training (PVT³ and ViT: embedding, attention output,
    /// feed-forward; RAEC: the latent code). The one home of the setting: `pvt3 train --dropout`
    /// writes it here.
    pub dropout: f64,
    pub layer_norm_eps: f64,
    /// The network and the fields only it has.
    pub network: Network,
}

/// A configuration file's dropout when it names none: the presets'.
fn default_dropout() -> f64 {
    0.1
}

fn default_eps() -> f64 {
    1e-5
}

/// The frequencies of a real transform of `frames` values, 0 to `frames / 2`: what the spectral
/// head (`crate::spectrum`) reads of each channel.
pub fn spectral_bins(frames: usize) -> usize {
    frames / 2 + 1
}

/// The refusal of what PVT³ alone does (pruning, baking, export, provisional answers), asked of
/// an `other` network: said once for the configuration and the trained model alike.
pub fn pvt3_only(what: &str, other: Architecture) -> Error {
    Error::Config(format!("{what}: PVT³ models only, and this is a {other} model"))
}

impl Config {
    pub fn architecture(&self) -> Architecture {
        self.network.architecture()
    }

    /// RAEC's own fields, if this is a RAEC.
    pub fn raec(&self) -> Option<&RaecConfig> {
        match &self.network {
            Network::Raec(r) => Some(r),
            _ => None,
        }
    }

    /// The spectral head's bands: 0 without one (and for every network but PVT³).
    pub fn spectral_bands(&self) -> usize {
        match &self.network {
            Network::Pvt3(p) => p.spectral_bands,
            _ => 0,
        }
    }

    /// Whether the spectral head reads the channels' levels (`Pvt3Config::spectral_levels`).
    pub fn spectral_levels(&self) -> bool {
        matches!(&self.network, Network::Pvt3(p) if p.spectral_levels)
    }

    /// Whether the spectral head reads an image's space (`Pvt3Config::spectral_space`).
    pub fn spectral_space(&self) -> bool {
        matches!(&self.network, Network::Pvt3(p) if p.spectral_space && p.spectral_bands > 0)
    }

    /// The bins of a head over the image's space's histogram (`Pvt3Config::spectral_histogram`); 0
    /// without one.
    pub fn spectral_histogram(&self) -> usize {
        match &self.network {
            Network::Pvt3(p) if self.spectral_space() => p.spectral_histogram,
            _ => 0,
        }
    }

    /// Whether a head with a histogram also reads its colours' gradients' histograms
    /// (`Pvt3Config::spectral_gradients`).
    pub fn spectral_gradients(&self) -> bool {
        matches!(&self.network, Network::Pvt3(p) if p.spectral_gradients && self.spectral_histogram() > 0)
    }

    /// Whether a head over the image's space averages its frames' log ring powers
    /// (`Pvt3Config::spectral_log_frames`).
    pub fn spectral_log_frames(&self) -> bool {
        matches!(&self.network, Network::Pvt3(p) if p.spectral_log_frames && self.spectral_space())
    }

    /// Whether a head over the image's space reads each colour's pixels
    /// (`Pvt3Config::spectral_pixels`).
    pub fn spectral_pixels(&self) -> bool {
        matches!(&self.network, Network::Pvt3(p) if p.spectral_pixels && self.spectral_space())
    }

    /// The histograms a head over the image's space reads of each colour, each of
    /// `spectral_histogram` bins (`spectrum::space::Histogram`): the values' and, with
    /// gradients, the differences across and down; none without a histogram.
    pub fn spectral_histograms(&self) -> &'static [crate::spectrum::space::Histogram] {
        use crate::spectrum::space::Histogram;
        match (self.spectral_histogram(), self.spectral_gradients()) {
            (0, _) => &[],
            (_, false) => &[Histogram::Values],
            (_, true) => &Histogram::ALL,
        }
    }

    /// Whether the model has a patch-selection mask (`Pvt3Config::patch_selection`).
    pub fn patch_selection(&self) -> bool {
        matches!(&self.network, Network::Pvt3(p) if p.patch_selection)
    }

    /// The share of patches a training step drops (`Pvt3Config::patch_dropout`); 0 for other networks.
    pub fn patch_dropout(&self) -> f64 {
        match &self.network {
            Network::Pvt3(p) => p.patch_dropout,
            _ => 0.0,
        }
    }

    /// Checks that the sizes fit together.
    pub fn validate(&self) -> Result<()> {
        if let Some((name, _)) = self.sizes().iter().find(|(_, v)| *v == 0) {
            return Err(Error::Config(format!("{name} must be at least 1")));
        }
        for (name, p) in [("dropout", self.dropout), ("patch_dropout", self.patch_dropout())] {
            if !(0.0..1.0).contains(&p) {
                return Err(Error::Config(format!("{name} = {p} is not in [0, 1)")));
            }
        }
        for (pn, p, n, v) in self.divisions()? {
            if v % p != 0 {
                return Err(Error::Config(format!("{pn} = {p} does not divide {n} = {v}")));
            }
        }
        Ok(())
    }

    /// The sizes that must be at least 1, by name: the window's, the transformer's and the
    /// network's own.
    fn sizes(&self) -> Vec<(&'static str, usize)> {
        let mut sizes = vec![
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
        match &self.network {
            Network::Pvt3(_) => {}
            Network::Vit(v) => sizes.push(("tile_rows", v.tile_rows)),
            Network::Raec(r) => sizes.extend([("rnn_hidden", r.rnn_hidden), ("latent", r.latent)]),
        }
        sizes
    }

    /// What must divide what for the network (a size and its name, then the divided one's), once
    /// the network's own checks pass.
    fn divisions(&self) -> Result<Vec<(&'static str, usize, &'static str, usize)>> {
        match &self.network {
            Network::Pvt3(p) => {
                self.validate_spectral(p)?;
                Ok(vec![
                    ("patch_height", self.patch_height, "height", self.height),
                    ("patch_width", self.patch_width, "width", self.width),
                    ("tubelet", self.tubelet, "frames", self.frames),
                ])
            }
            Network::Vit(v) => {
                if self.tubelet != 1 {
                    return Err(Error::Config(format!("tubelet = {}: ViT tiles single frames; tubelet must be 1", self.tubelet)));
                }
                let (th, tw) = self.tiled_size();
                Ok(vec![
                    ("tile_rows", v.tile_rows, "frames", self.frames),
                    ("patch_height", self.patch_height, "the tiled frame's height", th),
                    ("patch_width", self.patch_width, "the tiled frame's width", tw),
                ])
            }
            Network::Raec(r) => {
                self.validate_raec(r)?;
                Ok(vec![("tubelet", self.tubelet, "frames", self.frames)])
            }
        }
    }

    /// Checks that a RAEC's convolution fits the frame: single frames, room for its 2 × 2
    /// pooling, and an output that pooling tiles where the decoder mirrors it.
    fn validate_raec(&self, r: &RaecConfig) -> Result<()> {
        if self.tubelet != 1 && r.conv_channels > 0 {
            return Err(Error::Config(format!(
                "tubelet = {}: a RAEC with a convolution reads single frames; tubelet must be 1",
                self.tubelet
            )));
        }
        let (ch, cw) = r.conv_output(self);
        if r.conv_channels > 0 && (ch < 2 || cw < 2) {
            return Err(Error::Config(format!(
                "a {} × {} convolution and 2 × 2 pooling do not fit a {} × {} frame",
                self.patch_height, self.patch_width, self.height, self.width
            )));
        }
        if r.decoder_mirrors_conv() && (ch % 2 != 0 || cw % 2 != 0) {
            return Err(Error::Config(format!(
                "decoder_from_state un-pools the {ch} × {cw} convolution output, which 2 × 2 pooling must tile"
            )));
        }
        Ok(())
    }

    /// Checks that PVT³'s spectral head fits the window: its bands the frames' frequencies (or
    /// the image's rings), and a histogram only over an image's space, of at least 2 bins.
    fn validate_spectral(&self, p: &Pvt3Config) -> Result<()> {
        if p.spectral_histogram != 0 && !self.spectral_space() {
            return Err(Error::Config(format!(
                "spectral_histogram = {}: only a spectral head over an image's space (spectral_space) reads a histogram; set spectral_histogram=0 too",
                p.spectral_histogram
            )));
        }
        if p.spectral_gradients && self.spectral_histogram() == 0 {
            return Err(Error::Config(
                "spectral_gradients = true: the gradients' histograms take the values' bins, and spectral_histogram is 0; set spectral_gradients=false too".into(),
            ));
        }
        if p.spectral_log_frames && !self.spectral_space() {
            return Err(Error::Config(
                "spectral_log_frames = true: only a spectral head over an image's space (spectral_space) reads frames apart; set spectral_log_frames=false too".into(),
            ));
        }
        // Without a head (no bands), nothing reads the pixels, and `--set spectral_bands=0` alone
        // takes a camera's head away; a head over the frames cannot read them.
        if p.spectral_pixels && p.spectral_bands > 0 && !p.spectral_space {
            return Err(Error::Config(
                "spectral_pixels = true: only a spectral head over an image's space (spectral_space) reads pixels; set spectral_pixels=false too".into(),
            ));
        }
        if p.spectral_histogram == 1 {
            return Err(Error::Config("spectral_histogram = 1: a histogram needs at least 2 bins (0 has none)".into()));
        }
        if self.spectral_space() {
            crate::spectrum::space::band_of(self.height, self.width, p.spectral_bands)?;
        } else if p.spectral_bands > self.frames / 2 {
            return Err(Error::Config(format!(
                "spectral_bands = {} is more than the {} frequencies above 0 of {} frames",
                p.spectral_bands,
                self.frames / 2,
                self.frames
            )));
        }
        Ok(())
    }

    /// Fails, naming `what`, unless this configuration is PVT³'s.
    pub fn require_pvt3(&self, what: &str) -> Result<()> {
        match self.architecture() {
            Architecture::Pvt3 => Ok(()),
            other => Err(pvt3_only(what, other)),
        }
    }

    /// ViT: rows and columns of the frame all frames are tiled into (the frame itself for the
    /// other networks).
    pub fn tiled_size(&self) -> (usize, usize) {
        match &self.network {
            Network::Vit(v) => (self.height * v.tile_rows, self.width * self.frames.div_ceil(v.tile_rows)),
            _ => (self.height, self.width),
        }
    }

    /// The values of one temporal token's frames (RAEC: of one step, which its decoder
    /// reconstructs): `tubelet` frames of every sensor channel.
    pub fn step_values(&self) -> usize {
        self.tubelet * self.sensor_channels()
    }

    /// The sensor channels of a window (taxels or electrodes, times colours), the rows the
    /// spectral head reads.
    pub fn sensor_channels(&self) -> usize {
        self.height * self.width * self.channels
    }

    /// Spatial patches per temporal token (ViT: patches of the tiled frame).
    pub fn num_patches(&self) -> usize {
        let (h, w) = self.tiled_size();
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
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validate_names_the_misfit() {
        let cfg = Config { patch_width: 3, ..Config::icub20() };
        let msg = cfg.validate().unwrap_err().to_string();
        assert!(msg.contains("patch_width = 3 does not divide width = 10"), "{msg}");
        let vit = Config { tubelet: 5, ..Config::preset("vit-icub20").unwrap() };
        assert!(vit.validate().unwrap_err().to_string().contains("tubelet must be 1"));
    }

    /// Each check names what fails, for every network: a size of 0, a dropout out of range, a
    /// size that does not divide, a RAEC's convolution that does not fit.
    #[test]
    fn every_misfit_is_refused_by_name() {
        #[track_caller]
        fn refused(cfg: Config) -> String {
            cfg.validate().unwrap_err().to_string()
        }
        let (icub, vit, raec) = (Config::icub20(), Config::preset("vit-icub20").unwrap(), Config::preset("raec-icub20").unwrap());
        for cfg in [&icub, &vit, &raec] {
            cfg.validate().unwrap();
            assert!(refused(Config { mlp_dim: 0, ..cfg.clone() }).contains("mlp_dim must be at least 1"));
            assert!(refused(Config { dropout: 1.0, ..cfg.clone() }).contains("dropout = 1 is not in [0, 1)"));
        }
        assert!(refused(Config { tubelet: 4, ..icub.clone() }).contains("tubelet = 4 does not divide frames = 75"));
        assert!(refused(Config { frames: 74, ..vit.clone() }).contains("tile_rows = 5 does not divide frames = 74"));
        assert!(
            refused(Config { network: Network::Vit(VitConfig { tile_rows: 0 }), ..vit.clone() }).contains("tile_rows must be at least 1")
        );
        let Network::Raec(r) = &raec.network else { unreachable!("a RAEC preset") };
        assert!(refused(Config { network: Network::Raec(RaecConfig { latent: 0, ..*r }), ..raec.clone() })
            .contains("latent must be at least 1"));
        assert!(refused(Config { tubelet: 5, ..raec.clone() }).contains("a RAEC with a convolution reads single frames"));
        assert!(refused(Config { patch_height: 6, ..raec.clone() }).contains("do not fit a 6 × 10 frame"));
    }
}
