//! The spectral head of PVT³ (`Config::spectral_bands() > 0`): what a texture's vibration says,
//! given to the network directly. For each sensor channel, its mean level (unless
//! `spectral_levels` is off) and the log power of `spectral_bands` frequency bands
//! (geometrically spaced) of its detrended signal, over the frames of the kept temporal tokens
//! received so far (`pvt3_spec::spectrum`'s docs: the whole window's at the end of a touch, so
//! the head streams and answers early like the transformer);
//! the features are standardised (a scale and a shift per feature, fitted to the training set by
//! the trainer and held there) and mapped linearly to class logits, which are added to the
//! transformer's. A logistic regression on such features alone is a strong texture classifier
//! (`bench/spectral_probe.py`); the head puts that inside the one model that is exported.
//!
//! Over an image's space (`spectral_space`), the features are each colour's level, ring
//! powers and histogram (`spectral_histogram`) of every frame (`pvt3_spec::spectrum::space`),
//! averaged over the same frames: a camera's texture and press wherever the imprint lies; and
//! with `spectral_pixels` its pixels so averaged: where the gel is pressed.
//!
//! The transform is a plain product with `[cos | sin]` columns here (the trainer's candle graph),
//! and a Fourier transform op in the exported graph; the f64 reference computes it from the same
//! [`dft_matrix`] (the band maths live in `pvt3_spec::spectrum`).

use candle_core::{DType, Device, Tensor, D};
use candle_nn::{linear, Init, Linear, Module, VarBuilder};
use pvt3_spec::names;
use pvt3_spec::spectrum::{band_matrix, bins, dft_matrix, space, weighed_frames, POWER_FLOOR};

use crate::Config;

#[derive(Clone, Debug)]
pub struct Spectrum {
    /// What it transforms, and the constants of the transform.
    over: Over,
    /// `[features]` each: the standardisation, `feature · scale + shift`.
    scale: Tensor,
    shift: Tensor,
    linear: Linear,
    channels: usize,
    frames: usize,
    /// `Config::spectral_levels`.
    levels: bool,
}

/// What a spectral head transforms: each channel's frames, or each frame's image (`spectral_space`),
/// whose bands are rings of the image's frequencies and need no frequencies of the frames (a touch
/// of one frame has one).
#[derive(Clone, Debug)]
enum Over {
    /// [`dft_matrix`] and [`band_matrix`], constants.
    Frames {
        dft: Tensor,
        bands: Tensor,
    },
    Space(Space),
}

/// The constants of a head over the image's space: the width's and the height's `[cos | sin]`
/// matrices, the ring means of the powers `[kx][ky]` and the histogram's differences.
#[derive(Clone, Debug)]
struct Space {
    width: Tensor,
    height: Tensor,
    rings: Tensor,
    /// `space::histogram_matrix`'s `[bins − 1, bins]` and `[bins]`, when the head has a histogram.
    histogram: Option<(Tensor, Tensor)>,
    /// What it takes histograms of (`Config::spectral_histograms`).
    histograms: &'static [space::Histogram],
    /// Height, width, colours and bands.
    dims: (usize, usize, usize, usize),
    /// `Config::spectral_log_frames`: a window's log ring powers are its frames' mean.
    log_frames: bool,
    /// `Config::spectral_pixels`: each colour's pixels are features.
    pixels: bool,
}

/// A head over the image's space's quantities of each frame of a batch: `[b, frames, colours]`
/// levels, `[b, frames, colours · bands]` ring powers, `[b, frames, colours · bins]` histograms
/// and `[b, frames, colours · h · w]` pixels.
struct PerFrame {
    level: Tensor,
    power: Tensor,
    histogram: Option<Tensor>,
    pixels: Option<Tensor>,
}

impl Space {
    fn new(cfg: &Config) -> candle_core::Result<Self> {
        let (h, w, bands, bins) = (cfg.height, cfg.width, cfg.spectral_bands(), cfg.spectral_histogram());
        let k = space::width_bins(w);
        let rings = space::ring_means(h, w, bands).map_err(candle_core::Error::wrap)?;
        let constant = |v: Vec<f64>, shape: (usize, usize)| Tensor::from_vec(v, shape, &Device::Cpu)?.to_dtype(DType::F32);
        let histogram = match bins {
            0 => None,
            _ => {
                let (d, first) = space::histogram_matrix(bins);
                Some((constant(d, (bins - 1, bins))?, constant(first, (1, bins))?))
            }
        };
        Ok(Self {
            width: constant(space::cos_sin_matrix(w, k), (w, 2 * k))?,
            height: constant(space::cos_sin_matrix(h, h), (h, 2 * h))?,
            rings: constant(rings, (k * h, bands))?,
            histogram,
            histograms: cfg.spectral_histograms(),
            dims: (h, w, cfg.channels, bands),
            log_frames: cfg.spectral_log_frames(),
            pixels: cfg.spectral_pixels(),
        })
    }

    /// Each colour's histogram `[rows, bins]` of `pixels` `[rows, h · w]`: the mean share above
    /// each interior edge, then the bins' differences; none without a histogram.
    fn histogram(&self, pixels: &Tensor) -> candle_core::Result<Option<Tensor>> {
        let Some((d, first)) = &self.histogram else { return Ok(None) };
        let bins = first.dim(1)?;
        let width = space::histogram_width(bins);
        let above = space::histogram_edges(bins)
            .into_iter()
            .map(|e| pixels.affine(1.0 / width, 0.5 - e / width)?.clamp(0f32, 1f32)?.mean_keepdim(D::Minus1))
            .collect::<candle_core::Result<Vec<_>>>()?;
        Tensor::cat(&above, 1)?.matmul(d)?.broadcast_add(first).map(Some)
    }

    /// Each colour's histograms `[rows, kinds · bins]` of `frames` `[b, t, colours, h, w]`, each
    /// kind's ([`Space::histograms`]) bins in turn; none without a histogram.
    fn histograms(&self, frames: &Tensor) -> candle_core::Result<Option<Tensor>> {
        if self.histograms.is_empty() {
            return Ok(None);
        }
        let (h, w, _, _) = self.dims;
        let rows = frames.dims()[..3].iter().product::<usize>();
        let of = |kind: &space::Histogram| -> candle_core::Result<Option<Tensor>> {
            let values = match kind {
                space::Histogram::Values => frames.clone(),
                space::Histogram::Across => (frames.narrow(4, 1, w - 1)? - frames.narrow(4, 0, w - 1)?)?,
                space::Histogram::Down => (frames.narrow(3, 1, h - 1)? - frames.narrow(3, 0, h - 1)?)?,
            };
            self.histogram(&values.reshape((rows, kind.values(h, w)))?)
        };
        let each = self.histograms.iter().map(of).collect::<candle_core::Result<Option<Vec<_>>>>()?;
        each.map(|each| Tensor::cat(&each, 1)).transpose()
    }

    /// The levels, ring powers and histograms of each frame of windows `[b, h, w, (colours,)
    /// frames]`.
    fn per_frame(&self, x: &Tensor) -> candle_core::Result<PerFrame> {
        let (h, w, c, bands) = self.dims;
        let (b, t, k) = (x.dim(0)?, x.dim(D::Minus1)?, space::width_bins(w));
        let frames = x.reshape((b, h, w, c, t))?.permute((0, 4, 3, 1, 2))?.contiguous()?;
        let pixels = frames.reshape((b * t * c, h * w))?;
        let level = pixels.mean(D::Minus1)?.reshape((b, t, c))?;
        let histogram = self.histograms(&frames)?.map(|h| h.reshape((b, t, ()))).transpose()?;
        let pixel_values = self.pixels.then(|| frames.reshape((b, t, c * h * w))).transpose()?;
        let rows = frames.reshape((b * t * c * h, w))?.matmul(&self.width)?.reshape((b * t * c, h, 2 * k))?;
        let columns = rows.transpose(1, 2)?.contiguous()?.reshape((b * t * c * 2 * k, h))?.matmul(&self.height)?;
        let z = columns.reshape((b * t * c, 2 * k, 2 * h))?;
        let block = |i: usize, j: usize| z.narrow(1, i * k, k)?.narrow(2, j * h, h);
        let real = (block(0, 0)? - block(1, 1)?)?;
        let imaginary = (block(0, 1)? + block(1, 0)?)?;
        let power = (real.sqr()? + imaginary.sqr()?)?.reshape((b * t * c, k * h))?.matmul(&self.rings)?;
        Ok(PerFrame { level, power: power.reshape((b, t, c * bands))?, histogram, pixels: pixel_values })
    }
}

/// What a head over the image's space reads of each row (a window, or one frame of it):
/// `[rows, colours]` levels, `[rows, colours · bands]` log ring powers, `[rows, colours · bins]`
/// histograms and `[rows, colours · h · w]` pixels.
struct Read {
    level: Tensor,
    log_power: Tensor,
    histogram: Option<Tensor>,
    pixels: Option<Tensor>,
}

/// The logarithm of powers, `POWER_FLOOR` added so that a silent band is finite.
fn log(power: &Tensor) -> candle_core::Result<Tensor> {
    (power + POWER_FLOOR)?.log()
}

impl Spectrum {
    /// `vb` is the model's root; the head's variables are `spectral.{scale, shift, linear.*}`.
    pub fn new(cfg: &Config, vb: VarBuilder) -> candle_core::Result<Self> {
        let (t, b, f) = (cfg.frames, cfg.spectral_bands(), cfg.spectral_features());
        let constant = |v: Vec<f64>, shape: (usize, usize)| Tensor::from_vec(v, shape, &Device::Cpu)?.to_dtype(DType::F32);
        let vb = vb.pp(names::SPECTRAL);
        let over = match cfg.spectral_space() {
            true => Over::Space(Space::new(cfg)?),
            false => {
                Over::Frames { dft: constant(dft_matrix(t), (t, 2 * bins(t)))?, bands: constant(band_matrix(t, b), (2 * bins(t), b))? }
            }
        };
        Ok(Self {
            over,
            scale: vb.get_with_hints(f, names::SCALE, Init::Const(1.0))?,
            shift: vb.get_with_hints(f, names::SHIFT, Init::Const(0.0))?,
            linear: linear(f, cfg.classes, vb.pp(names::LINEAR))?,
            channels: cfg.sensor_channels(),
            frames: t,
            levels: cfg.spectral_levels(),
        })
    }

    /// The unstandardised features `[b, channels · (1 + bands)]` of windows `[b, h, w, (c,) t]`
    /// from the frames `weights` selects (`[t]`, `pvt3_spec::spectrum::frame_weights`): per
    /// channel its mean level (unless the levels are off: `[b, channels · bands]`), then the log
    /// power of each band of the detrended signal.
    pub fn features(&self, x: &Tensor, weights: &[f64]) -> candle_core::Result<Tensor> {
        let b = x.dim(0)?;
        let weighed = weighed_frames(weights);
        let w = Tensor::from_iter(weights.iter().map(|v| *v as f32), x.device())?.reshape((1, self.frames))?;
        let (dft, bands) = match &self.over {
            Over::Frames { dft, bands } => (dft, bands),
            Over::Space(space) => {
                let f = space.per_frame(x)?;
                let mean = |v: &Tensor| v.broadcast_mul(&w.reshape((1, self.frames, 1))?)?.sum(1)? / weighed;
                let histogram = f.histogram.as_ref().map(mean).transpose()?;
                let pixels = f.pixels.as_ref().map(mean).transpose()?;
                let log_power = match space.log_frames {
                    true => mean(&log(&f.power)?)?,
                    false => log(&mean(&f.power)?)?,
                };
                let read = Read { level: mean(&f.level)?, log_power, histogram, pixels };
                return self.space_features(space, &read, b);
            }
        };
        let rows = x.reshape((b * self.channels, self.frames))?;
        let level = (rows.broadcast_mul(&w)?.sum_keepdim(D::Minus1)? / weighed)?;
        let transform = rows.broadcast_sub(&level)?.broadcast_mul(&w)?.matmul(dft)?;
        let power = (transform.sqr()?.matmul(bands)? * (self.frames as f64 / weighed))?;
        let log_power = log(&power)?;
        let features = if self.levels { Tensor::cat(&[&level, &log_power], 1)? } else { log_power };
        features.reshape((b, ()))
    }

    /// The features of each frame alone of windows `[b, h, w, (c,) t]` over an image's space,
    /// `[b · kept, features]` for the frames `weights` keeps (as [`Spectrum::features`] of a
    /// window whose one received frame it is): the rows a head over the image's space is fitted
    /// to (`pvt3_trainer`'s `spectrum_fit`), 25 a touch where a touch alone is one.
    pub fn frame_features(&self, x: &Tensor, weights: &[f64]) -> candle_core::Result<Tensor> {
        let Over::Space(space) = &self.over else {
            return Err(candle_core::Error::Msg("features by frame: a head over an image's space only".into()));
        };
        let kept: Vec<u32> = (0..self.frames).filter(|n| weights[*n] > 0.0).map(|n| n as u32).collect();
        let kept = Tensor::new(kept.as_slice(), x.device())?;
        let f = space.per_frame(x)?;
        let (b, n) = (x.dim(0)?, kept.dim(0)?);
        let frames = |v: &Tensor| v.index_select(&kept, 1)?.reshape((b * n, ()));
        let read = Read {
            level: frames(&f.level)?,
            log_power: log(&frames(&f.power)?)?,
            histogram: f.histogram.as_ref().map(frames).transpose()?,
            pixels: f.pixels.as_ref().map(frames).transpose()?,
        };
        self.space_features(space, &read, b * n)
    }

    /// `[rows, features]`: per colour its level (unless the levels are off), log ring powers,
    /// histogram and pixels, from what `read` holds of each row.
    fn space_features(&self, space: &Space, read: &Read, rows: usize) -> candle_core::Result<Tensor> {
        let (c, bands) = (space.dims.2, space.dims.3);
        let mut parts = Vec::with_capacity(4);
        if self.levels {
            parts.push(read.level.reshape((rows, c, 1))?);
        }
        parts.push(read.log_power.reshape((rows, c, bands))?);
        for part in [&read.histogram, &read.pixels].into_iter().flatten() {
            parts.push(part.reshape((rows, c, ()))?);
        }
        Tensor::cat(&parts, 2)?.reshape((rows, ()))
    }

    /// Logits `[b, classes]` from the frames `weights` selects.
    pub fn forward(&self, x: &Tensor, weights: &[f64]) -> candle_core::Result<Tensor> {
        let standard = self.features(x, weights)?.broadcast_mul(&self.scale)?.broadcast_add(&self.shift)?;
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
            network: Pvt3Config { spectral_bands: 4, ..Default::default() }.into(),
            ..Config::icub20()
        };
        let vb = VarBuilder::zeros(DType::F32, &Device::Cpu);
        let head = Spectrum::new(&cfg, vb).unwrap();
        let wave: Vec<f32> = (0..40).map(|n| 3.0 + 2.0 * (2.0 * std::f32::consts::PI * 5.0 * n as f32 / 40.0).sin()).collect();
        let x = Tensor::from_vec(wave, (1, 1, 1, 40), &Device::Cpu).unwrap();
        let f: Vec<f32> = head.features(&x, &[1.0; 40]).unwrap().flatten_all().unwrap().to_vec1().unwrap();
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

    /// Without levels, the features are the band powers alone: a channel's level moved, as a
    /// press or the sliding direction moves it, changes none of them.
    #[test]
    fn without_levels_a_channel_s_level_is_not_read() {
        let cfg = Config { frames: 40, height: 2, width: 1, patch_height: 1, patch_width: 1, ..Config::icub20() };
        let network = Pvt3Config { spectral_bands: 4, spectral_levels: false, ..Default::default() };
        let head = Spectrum::new(&Config { network: network.into(), ..cfg }, VarBuilder::zeros(DType::F32, &Device::Cpu)).unwrap();
        let window = |level: f32| -> Tensor {
            let v: Vec<f32> = (0..80).map(|i| if i < 40 { level } else { 0.0 } + ((i * 7) % 11) as f32).collect();
            Tensor::from_vec(v, (1, 2, 1, 40), &Device::Cpu).unwrap()
        };
        let features =
            |level: f32| -> Vec<f32> { head.features(&window(level), &[1.0; 40]).unwrap().flatten_all().unwrap().to_vec1().unwrap() };
        assert_eq!(features(0.0).len(), 2 * 4);
        let (low, high) = (features(0.0), features(30.0));
        assert!(low.iter().zip(&high).all(|(a, b)| (a - b).abs() < 1e-4), "{low:?} against {high:?}");
    }

    /// The frames a weight leaves out change nothing, and those it keeps do: the features of the
    /// first half of a window are those of the first half followed by anything.
    #[test]
    fn frames_outside_the_weights_are_not_read() {
        let cfg = Config { frames: 40, height: 2, width: 1, patch_height: 1, patch_width: 1, ..Config::icub20() };
        let cfg = Config { network: Pvt3Config { spectral_bands: 4, ..Default::default() }.into(), ..cfg };
        let head = Spectrum::new(&cfg, VarBuilder::zeros(DType::F32, &Device::Cpu)).unwrap();
        let weights: Vec<f64> = (0..40).map(|n| if n < 20 { 1.0 } else { 0.0 }).collect();
        let window = |tail: f32| -> Tensor {
            let v: Vec<f32> = (0..80).map(|i| if i % 40 < 20 { ((i * 7) % 11) as f32 } else { tail * i as f32 }).collect();
            Tensor::from_vec(v, (1, 2, 1, 40), &Device::Cpu).unwrap()
        };
        let features = |x: &Tensor, w: &[f64]| -> Vec<f32> { head.features(x, w).unwrap().flatten_all().unwrap().to_vec1().unwrap() };
        assert_eq!(features(&window(0.0), &weights), features(&window(-3.5), &weights));
        assert_ne!(features(&window(0.0), &[1.0; 40]), features(&window(-3.5), &[1.0; 40]));
    }

    /// A head over the image's space with histograms: a frame's features by frame are those of a
    /// window whose one received frame it is, a frame of one value has its histogram in that
    /// value's bin (shared with the next where it lies between their centres), and the gradients'
    /// histograms bin the differences across and down.
    #[test]
    fn frames_alone_are_windows_of_one_frame_and_the_histogram_bins_values() {
        let network =
            Pvt3Config { spectral_bands: 3, spectral_space: true, spectral_histogram: 6, spectral_gradients: true, ..Default::default() };
        let cfg = Config {
            frames: 4,
            height: 16,
            width: 16,
            channels: 1,
            patch_height: 16,
            patch_width: 16,
            network: network.into(),
            ..Config::icub20()
        };
        let head = Spectrum::new(&cfg, VarBuilder::zeros(DType::F32, &Device::Cpu)).unwrap();
        // Frame n: a ramp across the image around a level of n − 2, the last frame all 1.25.
        let v: Vec<f32> = (0..16 * 16 * 4)
            .map(|i| {
                let (p, n) = (i / 4, i % 4);
                if n == 3 {
                    1.25
                } else {
                    n as f32 - 2.0 + (p % 16) as f32 / 16.0
                }
            })
            .collect();
        let x = Tensor::from_vec(v, (1, 16, 16, 4), &Device::Cpu).unwrap();
        let rows: Vec<Vec<f32>> = head.frame_features(&x, &[1.0, 0.0, 1.0, 1.0]).unwrap().to_vec2().unwrap();
        assert_eq!((rows.len(), rows[0].len()), (3, cfg.spectral_features()));
        for (row, n) in rows.iter().zip([0, 2, 3]) {
            let alone: Vec<f64> = (0..4).map(|m| if m == n { 1.0 } else { 0.0 }).collect();
            let window: Vec<f32> = head.features(&x, &alone).unwrap().flatten_all().unwrap().to_vec1().unwrap();
            assert!(row.iter().zip(&window).all(|(a, b)| (a - b).abs() < 1e-5), "frame {n}: {row:?} against {window:?}");
        }
        // Bins of width 1 over ±3: 1.25 lies three quarters of the way from bin 3's centre (0.5)
        // to bin 4's (1.5), so bin 4 holds 0.75 of it and bin 3 0.25.
        // Then the gradients': a flat frame's differences are all 0, on the edge between bins 2 and
        // 3; the ramp's across are 1 / 16, 0.5625 of the way from bin 2's centre to bin 3's.
        let close = |got: &[f32], want: &[f64]| got.len() == want.len() && got.iter().zip(want).all(|(a, b)| (*a as f64 - b).abs() < 1e-6);
        let flat = [0.0, 0.0, 0.0, 0.25, 0.75, 0.0, 0.0, 0.0, 0.5, 0.5, 0.0, 0.0, 0.0, 0.0, 0.5, 0.5, 0.0, 0.0];
        assert!(close(&rows[2][1 + 3..], &flat), "{:?}", &rows[2][1 + 3..]);
        let ramp_gradients = [0.0, 0.0, 0.4375, 0.5625, 0.0, 0.0, 0.0, 0.0, 0.5, 0.5, 0.0, 0.0];
        assert!(close(&rows[0][1 + 3 + 6..], &ramp_gradients), "{:?}", &rows[0][1 + 3 + 6..]);
    }

    /// With `spectral_log_frames` a window's features are the mean of its kept frames'; without,
    /// its ring powers' logarithms are those of the frames' mean power, larger by Jensen's
    /// inequality where the frames' powers differ.
    #[test]
    fn log_frames_average_the_frames_features() {
        let cfg = |log_frames| Config {
            frames: 3,
            height: 16,
            width: 16,
            channels: 1,
            patch_height: 16,
            patch_width: 16,
            network: Pvt3Config {
                spectral_bands: 3,
                spectral_space: true,
                spectral_histogram: 4,
                spectral_log_frames: log_frames,
                ..Default::default()
            }
            .into(),
            ..Config::icub20()
        };
        // Frame n: a ramp across the image n + 1 steep, so that the frames' powers differ.
        let v: Vec<f32> = (0..16 * 16 * 3).map(|i| ((i / 3) % 16) as f32 * ((i % 3) + 1) as f32 / 16.0).collect();
        let x = Tensor::from_vec(v, (1, 16, 16, 3), &Device::Cpu).unwrap();
        let weights = [1.0, 0.0, 1.0];
        let features = |log_frames| {
            let head = Spectrum::new(&cfg(log_frames), VarBuilder::zeros(DType::F32, &Device::Cpu)).unwrap();
            let window: Vec<f32> = head.features(&x, &weights).unwrap().flatten_all().unwrap().to_vec1().unwrap();
            let rows: Vec<Vec<f32>> = head.frame_features(&x, &weights).unwrap().to_vec2().unwrap();
            (window, rows)
        };
        let (logs, rows) = features(true);
        let mean: Vec<f32> = (0..logs.len()).map(|i| (rows[0][i] + rows[1][i]) / 2.0).collect();
        assert!(logs.iter().zip(&mean).all(|(a, b)| (a - b).abs() < 1e-5), "{logs:?} against {mean:?}");
        let (of_mean, _) = features(false);
        assert!((1..4).all(|j| of_mean[j] > logs[j] + 0.01), "{of_mean:?} against {logs:?}");
        assert!(of_mean.iter().zip(&logs).enumerate().all(|(i, (a, b))| (1..4).contains(&i) || (a - b).abs() < 1e-6));
    }
}
