//! The spectral head of PVT³ (`Config::spectral_bands() > 0`): what a texture's vibration says,
//! given to the network directly. For each sensor channel of the window, its mean level and the
//! log power of `spectral_bands` frequency bands (geometrically spaced) of its detrended signal;
//! the features are standardised (a scale and a shift per feature, fitted to the training set by
//! the trainer and trained on) and mapped linearly to class logits, which are added to the
//! transformer's. A logistic regression on such features alone is a strong texture classifier
//! (`bench/spectral_probe.py`); the head puts that inside the one model that is exported.
//!
//! The transform is a plain product with `[cos | sin]` columns here (the trainer's candle graph),
//! and a Fourier transform op in the exported graph; the f64 reference computes it from the same
//! [`dft_matrix`] (the band maths live in `pvt3_spec::spectrum`).

use candle_core::{DType, Device, Tensor, D};
use candle_nn::{linear, Init, Linear, Module, VarBuilder};
use pvt3_spec::names;
use pvt3_spec::spectrum::{band_matrix, bins, dft_matrix, POWER_FLOOR};

use crate::Config;

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
        let (t, b, f) = (cfg.frames, cfg.spectral_bands(), cfg.spectral_features());
        let constant = |v: Vec<f64>, shape: (usize, usize)| Tensor::from_vec(v, shape, &Device::Cpu)?.to_dtype(DType::F32);
        let vb = vb.pp(names::SPECTRAL);
        Ok(Self {
            dft: constant(dft_matrix(t), (t, 2 * bins(t)))?,
            bands: constant(band_matrix(t, b), (2 * bins(t), b))?,
            scale: vb.get_with_hints(f, names::SCALE, Init::Const(1.0))?,
            shift: vb.get_with_hints(f, names::SHIFT, Init::Const(0.0))?,
            linear: linear(f, cfg.classes, vb.pp(names::LINEAR))?,
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
    use crate::Pvt3Config;
    use pvt3_spec::spectrum::band_edges;

    /// The features are what their definition says: a sine of frequency 5 and amplitude 2
    /// around a level of 3 has its power in the band holding frequency 5 and almost none
    /// elsewhere.
    #[test]
    fn a_sine_lands_in_its_band() {
        let cfg = Config {
            frames: 40,
            height: 1,
            width: 1,
            patch_height: 1,
            patch_width: 1,
            network: Pvt3Config { spectral_bands: 4 }.into(),
            ..Config::icub20()
        };
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
