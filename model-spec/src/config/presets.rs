//! The sensor presets (iCub-20, BioTac-20, GelSight), the layout derived for a sensor no preset
//! fits, and each preset's ViT and RAEC variants.

use super::network::{Architecture, Network, Pvt3Config, RaecConfig, VitConfig};
use super::Config;
use crate::{Error, Result, Sensor};

/// The sensor presets (PVT³); each also comes as `vit-NAME` and `raec-NAME`.
pub const PRESETS: [&str; 3] = ["icub20", "biotac20", "gelsight"];

/// About how many patches a derived layout cuts an image into: 3 × 4 of a 3:4 frame.
const IMAGE_PATCHES: f64 = 12.0;

/// Rings of spatial frequency the spectral head of a camera's layout reads (fewer where a small
/// image has not that many): its band powers alone classify PhysiCLeAR's objects better than the
/// transformer does (docs/camera.md, "The image's spectrum").
const IMAGE_BANDS: usize = 12;

/// Bins of the histogram beside the rings in a camera's layout (over ±3 standard deviations, a
/// quarter of one a bin): with it, PhysiCLeAR's objects read about 5 points better than by the
/// rings alone (docs/camera.md, "The press's histogram").
/// The histograms of the gradients across and down beside it (`Pvt3Config::spectral_gradients`)
/// are not the layout's: PhysiCLeAR's validation folds did not read better with them
/// (docs/camera.md, "The gradients' histograms").
const IMAGE_HISTOGRAM: usize = 24;

/// The divisor of `n` nearest `ideal` in ratio (the smaller of two as near).
fn nearest_divisor(n: usize, ideal: f64) -> usize {
    let distance = |d: usize| (d as f64 / ideal).ln().abs();
    (1..=n).filter(|d| n.is_multiple_of(*d)).min_by(|a, b| distance(*a).total_cmp(&distance(*b))).expect("1 divides every n")
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
            dropout: super::default_dropout(),
            layer_norm_eps: super::default_eps(),
            network: Pvt3Config::default().into(),
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

    /// A sensor no preset fits, of kind `sensor` (as its data set records it), samples `[height,
    /// width, (channels,) frames]`. The tubelet is the
    /// divisor of `frames` nearest (in ratio) to `frames / 40`, so that about 40 temporal tokens
    /// remain, as in the BioTac preset. Frames read as images ([`Sensor::reads_images`]: a camera's,
    /// a large taxel grid's) are cut into about 12 square patches (sides the divisors of height
    /// and width nearest `√(height · width / 12)`: 10 × 10 pixels of 30 × 40), with a spectral
    /// head over the image's space (rings, a histogram and the pixels), the rest the GelSight
    /// preset's. Other frames get the BioTac layout, which assumes no grid: all channels of a
    /// tubelet form one token (one patch covering the frame), the rest the BioTac preset's. `None` for a shape that is not 3 or 4 axes of
    /// positive lengths.
    pub fn for_sensor(sensor: Sensor, sample_shape: &[usize]) -> Option<Self> {
        let (height, width, channels, frames) = match *sample_shape {
            [h, w, f] => (h, w, 1, f),
            [h, w, c, f] => (h, w, c, f),
            _ => return None,
        };
        if [height, width, channels, frames].contains(&0) {
            return None;
        }
        let tubelet = nearest_divisor(frames, frames as f64 / 40.0);
        if !sensor.reads_images(height, width) {
            return Some(Self { height, width, channels, frames, patch_height: height, patch_width: width, tubelet, ..Self::biotac20() });
        }
        let side = ((height * width) as f64 / IMAGE_PATCHES).sqrt();
        let (patch_height, patch_width) = (nearest_divisor(height, side), nearest_divisor(width, side));
        let bands = (1..=IMAGE_BANDS).rev().find(|b| crate::spectrum::space::band_of(height, width, *b).is_ok()).unwrap_or(0);
        let histogram = if bands > 0 { IMAGE_HISTOGRAM } else { 0 };
        let network = Pvt3Config {
            spectral_bands: bands,
            spectral_space: bands > 0,
            spectral_histogram: histogram,
            spectral_pixels: bands > 0,
            ..Pvt3Config::default()
        }
        .into();
        Some(Self { height, width, channels, frames, patch_height, patch_width, tubelet, network, ..Self::gelsight() })
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

    /// A preset by the name a user gives: a sensor's ([`PRESETS`]), optionally prefixed `vit-` or
    /// `raec-` for that baseline.
    pub fn preset(name: &str) -> Result<Self> {
        let (model, sensor) = match name.split_once('-') {
            Some(("vit", sensor)) => (Architecture::Vit, sensor),
            Some(("raec", sensor)) => (Architecture::Raec, sensor),
            _ => (Architecture::Pvt3, name),
        };
        Self::sensor_preset(sensor, model).map_err(|_| Error::UnknownPreset(name.to_string()))
    }

    /// The preset of `sensor` ([`PRESETS`]) for the network `model`.
    pub fn sensor_preset(sensor: &str, model: Architecture) -> Result<Self> {
        let cfg = match sensor {
            "icub20" => Self::icub20(),
            "biotac20" => Self::biotac20(),
            "gelsight" => Self::gelsight(),
            _ => return Err(Error::UnknownPreset(sensor.to_string())),
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
            // A PVT³ layout keeps its own fields (a camera's spectral head).
            Architecture::Pvt3 if matches!(self.network, Network::Pvt3(_)) => self,
            Architecture::Pvt3 => Self { network: Network::new(model), ..self },
            Architecture::Vit => {
                let (patch_height, patch_width, tile_rows) = match (self.height, self.width) {
                    (h, 1) => (h, self.tubelet, 1),
                    (h, w) if h * w <= 64 => (h, w / 2, 5.min(self.frames)),
                    _ => (self.patch_height, self.patch_width, 1),
                };
                Self { network: VitConfig { tile_rows }.into(), patch_height, patch_width, tubelet: 1, ..self }
            }
            Architecture::Raec => {
                let conv = self.height >= 3 && self.width >= 5;
                let (patch_height, patch_width) = if conv { (3, 5) } else { (1, 1) };
                let (conv_channels, tubelet) = if conv { (3, 1) } else { (0, self.tubelet) };
                let network = RaecConfig { conv_channels, ..RaecConfig::default() }.into();
                Self { network, patch_height, patch_width, tubelet, ..self }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_validate_and_round_trip_through_json() {
        for name in PRESETS.into_iter().flat_map(|p| [p.to_string(), format!("vit-{p}"), format!("raec-{p}")]) {
            let cfg = Config::preset(&name).unwrap();
            cfg.validate().unwrap();
            let back: Config = serde_json::from_str(&serde_json::to_string(&cfg).unwrap()).unwrap();
            assert_eq!(back, cfg, "{name}");
        }
        assert!(matches!(Config::preset("nope"), Err(Error::UnknownPreset(_))));
    }

    /// A sensor without a preset gets the BioTac layout with about 40 temporal tokens, and the
    /// configuration validates and fits its samples.
    #[test]
    fn a_new_sensor_gets_the_biotac_layout() {
        for (shape, tubelet) in [(vec![24, 1, 250], 5), (vec![19, 1, 400], 10), (vec![4, 4, 3, 64], 2), (vec![8, 8, 37], 1)] {
            let cfg = Config::for_sensor(Sensor::of(&shape), &shape).unwrap();
            cfg.validate().unwrap();
            assert_eq!((cfg.sample_shape(), cfg.tubelet, cfg.num_patches()), (shape.clone(), tubelet, 1), "{shape:?}");
        }
        assert_eq!(Config::for_sensor(Sensor::of(&[19, 1, 400]), &[19, 1, 400]).unwrap(), Config::biotac20());
        assert!(
            Config::for_sensor(Sensor::of(&[10, 75]), &[10, 75]).is_none()
                && Config::for_sensor(Sensor::of(&[0, 1, 4]), &[0, 1, 4]).is_none()
        );
    }

    /// A camera's images are cut into about 12 patches, with the GelSight preset's widths.
    #[test]
    fn a_camera_gets_about_twelve_patches_a_frame() {
        for (shape, patch, tubelet) in [
            (vec![30, 40, 3, 25], [10, 10], 1),
            (vec![240, 320, 3, 25], [80, 80], 1),
            (vec![48, 64, 100], [16, 16], 2),
            (vec![16, 17, 3, 8], [4, 17], 1),
        ] {
            let cfg = Config::for_sensor(Sensor::of(&shape), &shape).unwrap();
            cfg.validate().unwrap();
            assert_eq!(
                (cfg.sample_shape(), [cfg.patch_height, cfg.patch_width], cfg.tubelet),
                (shape.clone(), patch, tubelet),
                "{shape:?}"
            );
            assert_eq!((cfg.dim, cfg.mlp_dim), (Config::gelsight().dim, Config::gelsight().mlp_dim));
        }
        assert_eq!(
            Config::for_sensor(Sensor::of(&[15, 40, 3, 25]), &[15, 40, 3, 25]).unwrap().num_patches(),
            1,
            "a grid narrower than an image"
        );
        let grid = [32, 32, 40];
        assert_eq!(
            Config::for_sensor(Sensor::Array, &grid),
            Config::for_sensor(Sensor::Camera, &grid),
            "a large taxel grid reads as an image"
        );
    }
}
