//! The spectral head of PVT³ (`Config::spectral_bands > 0`): what a texture's vibration says,
//! given to the network directly. For each sensor channel of the window, its mean level and the
//! log power of `spectral_bands` frequency bands (geometrically spaced) of its detrended signal;
//! the features are standardised (a scale and a shift per feature, fitted to the training set by
//! the trainer and trained on) and mapped linearly to class logits, which are added to the
//! transformer's. A logistic regression on such features alone is a strong texture classifier
//! (`bench/spectral_probe.py`); the head puts that inside the one model that is exported.
//!
//! The transform is a plain product with `[cos | sin]` columns here (the trainer's candle graph),
//! and a Fourier transform op in the exported graph; the f64 reference computes it from the same
//! [`dft_matrix`].

use candle_core::{DType, Device, Tensor, D};
use candle_nn::{linear, Init, Linear, Module, VarBuilder};

use crate::Config;

/// Power added before the logarithm (normalised units), so that a silent band is finite.
pub const POWER_FLOOR: f64 = 1e-6;

pub use crate::config::spectral_bins as bins;

/// Band `j` sums the power of frequencies `edges[j]..edges[j + 1]`: `bands` geometrically spaced
/// bands from frequency 1 (0, the level, is a feature of its own) to the last, each at least
/// one frequency wide. `bands` must be at most `frames / 2` ([`Config::validate`] checks).
pub fn band_edges(frames: usize, bands: usize) -> Vec<usize> {
    let top = bins(frames);
    let mut edges = vec![1];
    for j in 1..=bands {
        let geometric = (top as f64).powf(j as f64 / bands as f64).round() as usize;
        let lowest = edges[j - 1] + 1;
        edges.push(geometric.max(lowest).min(top - (bands - j)));
    }
    edges
}

/// `[frames, 2 · bins]` row-major: frame `n`'s `cos(2π k n / T) / √T` for each frequency `k`,
/// then its `sin`, so that a row vector of frames times it gives the transform's real and
/// (negated) imaginary parts, scaled so that white noise of unit variance has unit power.
pub fn dft_matrix(frames: usize) -> Vec<f64> {
    let k = bins(frames);
    let norm = (frames as f64).sqrt();
    let mut m = vec![0.0; frames * 2 * k];
    for n in 0..frames {
        for f in 0..k {
            let angle = 2.0 * std::f64::consts::PI * ((f * n) % frames) as f64 / frames as f64;
            m[n * 2 * k + f] = angle.cos() / norm;
            m[n * 2 * k + k + f] = angle.sin() / norm;
        }
    }
    m
}

/// `[2 · bins, bands]`: 1 where a real or imaginary part's square belongs to a band.
pub fn band_matrix(frames: usize, bands: usize) -> Vec<f64> {
    let k = bins(frames);
    let edges = band_edges(frames, bands);
    let mut m = vec![0.0; 2 * k * bands];
    for (j, w) in edges.windows(2).enumerate() {
        for f in w[0]..w[1] {
            m[f * bands + j] = 1.0;
            m[(k + f) * bands + j] = 1.0;
        }
    }
    m
}

#[derive(Clone, Debug)]
pub struct Spectrum {
    /// [`dft_matrix`], a constant.
    dft: Tensor,
    /// [`band_matrix`], a constant.
    bands: Tensor,
    /// `[features]` each: the standardisation, `feature · scale + shift`.
    scale: Tensor,
    shift: Tensor,
    linear: Linear,
    channels: usize,
    frames: usize,
}

impl Spectrum {
    /// `vb` is the model's root; the head's variables are `spectral.{scale, shift, linear.*}`.
    pub fn new(cfg: &Config, vb: VarBuilder) -> candle_core::Result<Self> {
        let (t, b, f) = (cfg.frames, cfg.spectral_bands, cfg.spectral_features());
        let constant = |v: Vec<f64>, shape: (usize, usize)| Tensor::from_vec(v, shape, &Device::Cpu)?.to_dtype(DType::F32);
        let vb = vb.pp("spectral");
        Ok(Self {
            dft: constant(dft_matrix(t), (t, 2 * bins(t)))?,
            bands: constant(band_matrix(t, b), (2 * bins(t), b))?,
            scale: vb.get_with_hints(f, "scale", Init::Const(1.0))?,
            shift: vb.get_with_hints(f, "shift", Init::Const(0.0))?,
            linear: linear(f, cfg.classes, vb.pp("linear"))?,
            channels: cfg.sensor_channels(),
            frames: t,
        })
    }

    /// The unstandardised features `[b, channels · (1 + bands)]` of windows `[b, h, w, (c,) t]`:
    /// per channel its mean level, then the log power of each band of the detrended signal.
    pub fn features(&self, x: &Tensor) -> candle_core::Result<Tensor> {
        let b = x.dim(0)?;
        let rows = x.reshape((b * self.channels, self.frames))?;
        let level = rows.mean_keepdim(D::Minus1)?;
        let transform = rows.broadcast_sub(&level)?.matmul(&self.dft)?;
        let power = transform.sqr()?.matmul(&self.bands)?;
        let log_power = (power + POWER_FLOOR)?.log()?;
        Tensor::cat(&[&level, &log_power], 1)?.reshape((b, ()))
    }

    /// Logits `[b, classes]`.
    pub fn forward(&self, x: &Tensor) -> candle_core::Result<Tensor> {
        let standard = self.features(x)?.broadcast_mul(&self.scale)?.broadcast_add(&self.shift)?;
        self.linear.forward(&standard)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_tile_the_frequencies_above_zero() {
        for (frames, bands) in [(400, 16), (75, 16), (75, 37), (10, 1), (11, 5)] {
            let e = band_edges(frames, bands);
            assert_eq!(e.len(), bands + 1);
            assert_eq!((e[0], e[bands]), (1, bins(frames)), "{frames} {bands}: {e:?}");
            assert!(e.windows(2).all(|w| w[0] < w[1]), "{frames} {bands}: {e:?}");
        }
        // Geometric (round(201^(j/16)), at least one wider than the last): one frequency wide at
        // the bottom, 57 at the top.
        let e = band_edges(400, 16);
        assert_eq!(e, [1, 2, 3, 4, 5, 6, 7, 10, 14, 20, 28, 38, 53, 74, 104, 144, 201]);
    }

    /// The features are what their definition says: a sine of frequency 5 and amplitude 2
    /// around a level of 3 has its power in the band holding frequency 5 and almost none
    /// elsewhere.
    #[test]
    fn a_sine_lands_in_its_band() {
        let cfg = Config { frames: 40, spectral_bands: 4, height: 1, width: 1, patch_height: 1, patch_width: 1, ..Config::icub20() };
        let vb = VarBuilder::zeros(DType::F32, &Device::Cpu);
        let head = Spectrum::new(&cfg, vb).unwrap();
        let wave: Vec<f32> = (0..40).map(|n| 3.0 + 2.0 * (2.0 * std::f32::consts::PI * 5.0 * n as f32 / 40.0).sin()).collect();
        let x = Tensor::from_vec(wave, (1, 1, 1, 40), &Device::Cpu).unwrap();
        let f: Vec<f32> = head.features(&x).unwrap().flatten_all().unwrap().to_vec1().unwrap();
        let edges = band_edges(40, 4);
        let band = edges.windows(2).position(|w| (w[0]..w[1]).contains(&5)).unwrap();
        assert!((f[0] - 3.0).abs() < 1e-5, "level {}", f[0]);
        // Power of a sine of amplitude A over T frames, split between ±5: (A²/2)·T/T… at bin 5
        // of the one-sided transform with the 1/√T scale: A² T / 4 = 40.
        assert!(((f[1 + band] as f64).exp() - 40.0).abs() < 1e-2, "{f:?}");
        for (j, v) in f[1..].iter().enumerate().filter(|(j, _)| *j != band) {
            assert!((*v as f64) < (2.0 * POWER_FLOOR).ln(), "band {j}: {v}");
        }
    }
}
