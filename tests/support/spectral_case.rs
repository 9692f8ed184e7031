//! A BioTac-shaped PVT³ with a spectral head (a standardisation and a normalisation other than
//! the identity, a third of its temporal tokens pruned; reading the channels' levels or not) and
//! raw windows for it: what the export test runs in onnxruntime and the runtime test in tract,
//! each against the f64 reference of the same baked model.

use pvt3_models::weights::varmap_tensors;
use pvt3_models::{Config, Pvt3, Rng};
use pvt3_spec::bake::bake;
use pvt3_spec::baked::BakedPvt3;
use pvt3_spec::normalization::Normalization;

pub struct SpectralCase {
    pub baked: BakedPvt3,
    pub norm: Normalization,
    /// `windows` raw windows `[19, 1, 400]`: a sine per electrode (its own frequency) and noise,
    /// around the electrode's mean.
    pub raw: Vec<f32>,
    /// The same, normalised: the reference's input.
    pub normalised: Vec<f32>,
}

pub fn spectral_case(windows: usize, levels: bool) -> SpectralCase {
    let network = pvt3_spec::Pvt3Config { spectral_bands: 16, spectral_levels: levels, ..Default::default() };
    let cfg = Config { network: network.into(), ..Config::biotac20() };
    let (_, varmap) = Pvt3::init(&cfg, 6).unwrap();
    let mut tensors = varmap_tensors(&varmap).unwrap();
    let mut rng = Rng::new(7);
    for name in ["spectral.scale", "spectral.shift"] {
        tensors.get_mut(name).unwrap().1.iter_mut().for_each(|v| *v = 0.5 + rng.normal().abs());
    }
    // Tokens 1, 4, 7, … pruned: the head reads neither their frames nor any after a prefix.
    tensors.get_mut("frame_mask").unwrap().1.iter_mut().enumerate().for_each(|(k, v)| *v = if k % 3 == 1 { 0.0 } else { 1.0 });
    let norm = Normalization {
        mean: (0..19).map(|_| 100.0 * rng.normal()).collect(),
        std: (0..19).map(|_| 1.0 + 20.0 * rng.normal().abs()).collect(),
        frames: 400,
    };
    let raw: Vec<f32> = (0..windows * 19 * 400)
        .map(|i| {
            let (c, t) = ((i / 400) % 19, (i % 400) as f32);
            norm.mean[c] + norm.std[c] * ((0.05 * (c + 1) as f32 * t).sin() + 0.3 * rng.normal())
        })
        .collect();
    let mut normalised = Vec::new();
    raw.chunks(19 * 400).for_each(|s| norm.apply_into(s, &mut normalised));
    SpectralCase { baked: bake(&cfg, &tensors).unwrap(), norm, raw, normalised }
}
