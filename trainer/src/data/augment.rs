//! Augmentation of training windows. Each window is changed alone as it is batched ([`augment`]:
//! a firmer or lighter press, a stronger or weaker vibration, a shift in time, the other sliding
//! direction, an image moved or mirrored, a gain and noise);
//! a batch as a whole is blended with itself ([`mixup`]) or pushed beyond its touches
//! ([`extrapolation`]) in the learner's forward pass.

pub mod extrapolation;
pub mod mixup;

use pvt3_models::Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::normalization::Normalization;

// The options' heading in `--help` (per argument: a heading set for a flattened group would hold
// for every argument after it too).
const AUGMENTATION: &str = "Augmentation";

/// How training windows are changed as they are batched ([`augment`]) and how a
/// batch is blended or pushed beyond its touches in the learner's forward pass.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, clap::Args)]
pub struct Augmentation {
    /// Each training sample is scaled by a random gain in [1 - g, 1 + g].
    #[arg(long = "aug-gain", id = "aug_gain", value_name = "AUG_GAIN", default_value_t = 0.1, help_heading = AUGMENTATION)]
    #[serde(rename = "aug_gain")]
    pub gain: f64,
    /// Gaussian noise of this standard deviation (in normalised units).
    #[arg(long = "aug-noise", id = "aug_noise", value_name = "AUG_NOISE", default_value_t = 0.05, help_heading = AUGMENTATION)]
    #[serde(rename = "aug_noise")]
    pub noise: f64,
    /// Shift each training sample in time by a random offset in [-N, N] frames
    /// (edge frames repeated).
    #[arg(long = "aug-shift", id = "aug_shift", value_name = "AUG_SHIFT", default_value_t = 0, help_heading = AUGMENTATION)]
    #[serde(default, rename = "aug_shift")]
    pub shift: usize,
    /// Multiply each training window's raw readings by a random factor,
    /// log-uniform in [1 / (1 + S), 1 + S], as a lighter or firmer press would (a capacitive
    /// sensor's readings grow about in proportion to the force: docs/robustness.md). E.g. 0.5.
    /// 0 turns it off.
    #[arg(long = "aug-scale", id = "aug_scale", value_name = "AUG_SCALE", default_value_t = 0.0, help_heading = AUGMENTATION)]
    #[serde(default, rename = "aug_scale")]
    pub scale: f64,
    /// Multiply each channel's raw readings in a training window by a random
    /// factor of its own, log-uniform in [1 / (1 + S), 1 + S]: the pattern of levels across the
    /// sensor distorted, as a press beyond the trained forces distorts it (docs/robustness.md,
    /// "What force does to the readings"). E.g. 0.05. 0 turns it off.
    #[arg(long = "aug-channel-scale", id = "aug_channel_scale", value_name = "AUG_CHANNEL_SCALE", default_value_t = 0.0, help_heading = AUGMENTATION)]
    #[serde(default, rename = "aug_channel_scale")]
    pub channel_scale: f64,
    /// Multiply each training window's variation about its mean (per channel, the
    /// level kept) by a random factor, log-uniform in [1 / (1 + S), 1 + S]: a firmer press makes
    /// a texture's vibration grow faster than the level (docs/robustness.md). E.g. 0.5. 0 turns
    /// it off.
    #[arg(long = "aug-vibration", id = "aug_vibration", value_name = "AUG_VIBRATION", default_value_t = 0.0, help_heading = AUGMENTATION)]
    #[serde(default, rename = "aug_vibration")]
    pub vibration: f64,
    /// Read each training window at a random speed, as if the touch had been made
    /// up to 1 + S times faster or slower (log-uniform; resampled, the touch's own frames beyond
    /// the window read where it has them), so that a model meets speeds it was not trained at.
    /// E.g. 1 (half to twice the speed). 0 turns it off.
    #[arg(long = "aug-stretch", id = "aug_stretch", value_name = "AUG_STRETCH", default_value_t = 0.0, help_heading = AUGMENTATION)]
    #[serde(default, rename = "aug_stretch")]
    pub stretch: f64,
    /// With probability P, reverse a training window in time, as if the sensor had slid over
    /// the same texture the other way: its ridges pass under the sensor in the reverse order
    /// (the sensor's layout is not mirrored). E.g. 0.5. 0 turns it off.
    #[arg(long = "aug-reverse", id = "aug_reverse", value_name = "AUG_REVERSE", default_value_t = 0.0, help_heading = AUGMENTATION)]
    #[serde(default, rename = "aug_reverse")]
    pub reverse: f64,
    /// Move each training window's image by up to N pixels (or taxels) each way, both axes drawn
    /// alone, edge pixels repeated: a camera's touch pressed a little elsewhere on the gel.
    /// 0 turns it off.
    #[arg(long = "aug-translate", id = "aug_translate", value_name = "AUG_TRANSLATE", default_value_t = 0, help_heading = AUGMENTATION)]
    #[serde(default, rename = "aug_translate")]
    pub translate: usize,
    /// With probability P each, mirror a training window's image left to right, and top to
    /// bottom (drawn alone): a texture's surface is as likely the one way round as the other, and
    /// both mirrors together turn it half round. For an image's rows and columns, where the image
    /// looks alike mirrored: not a GelSight's colour image, lit from fixed sides
    /// (docs/camera.md), nor a grid of taxels that is not a picture. E.g. 0.5. 0 turns it off.
    #[arg(long = "aug-flip", id = "aug_flip", value_name = "AUG_FLIP", default_value_t = 0.0, help_heading = AUGMENTATION)]
    #[serde(default, rename = "aug_flip")]
    pub flip: f64,
    /// Mixup: blend each training batch with a shuffled copy of itself, λ ~ Beta(α, α) per batch,
    /// and the two labels' losses alike; this is α (e.g. 0.2). 0 turns it off.
    #[arg(long, default_value_t = 0.0, help_heading = AUGMENTATION)]
    #[serde(default)]
    pub mixup: f64,
    /// Same-class extrapolation: move each training sample away from another of its class in the
    /// batch, x + λ (x − x_p) with λ ~ U(0, L) per sample, its label kept; this is L (e.g. 1).
    /// The step between two touches of a material continues past them, as a press firmer or
    /// lighter than any trained would: with 1, unseen forces 0.96 instead of 0.86 on FabricSlide
    /// (docs/robustness.md). 0 turns it off.
    #[arg(long, default_value_t = 0.0, help_heading = AUGMENTATION)]
    #[serde(default)]
    pub extrapolate: f64,
    /// With --extrapolate: move only each channel's level (its mean over the window) and keep the
    /// window's own variation. Two touches' vibrations are not aligned in time, so their
    /// difference is noise that a whole-window step adds to the sample: on FabricSlide the levels
    /// alone keep unseen firmer presses at 0.95 and a lighter one at 0.95, where whole windows
    /// give 0.96 and 0.88 (docs/robustness.md).
    #[arg(long, requires = "extrapolate", help_heading = AUGMENTATION)]
    #[serde(default)]
    pub extrapolate_levels: bool,
    /// Training for ways of touching beyond the trained ones. `auto`: where the touches that
    /// train were made in more than one recorded way (a condition of `pvt3 import --name`, such
    /// as force or speed, in two levels or more) and neither --aug-channel-scale nor --extrapolate
    /// is asked, train with `--aug-channel-scale 0.15`, `--aug-stretch 1` unless a stretch is
    /// asked, and a PVT³ of a sensor's channels with `--set spectral_bands=16` unless the bands are
    /// set, and say so (what it changes: docs/robustness.md); a set that records no conditions
    /// trains as asked. `on`: as if it recorded them; `off`: as asked.
    #[arg(long, value_enum, default_value_t = Robust::Auto, help_heading = AUGMENTATION)]
    #[serde(default = "Robust::before_auto")]
    pub robust: Robust,
}

/// Whether training prepares a model for ways of touching beyond the trained ones
/// (`configure::robust`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Robust {
    /// Where the data record that the touches were made in more than one way.
    Auto,
    /// Always.
    On,
    /// Never: the augmentations as asked.
    Off,
}

impl Robust {
    /// What a run recorded before `--robust` was: its options as asked.
    fn before_auto() -> Self {
        Robust::Off
    }
}

/// One normalised training window (`norm.frames` frames a channel, channels in rows, `grid`'s
/// height × width × colours of them) changed in place as `opts` asks: its raw readings scaled per
/// window and per channel, its variation about each channel's mean scaled, shifted in time (edge
/// frames repeated), reversed in time, its image moved and mirrored, then a gain and Gaussian
/// noise; each draw from `rng`, in that order (an option that is off draws nothing).
pub fn augment(sample: &mut [f32], norm: &Normalization, grid: [usize; 3], opts: &Augmentation, rng: &mut Rng) {
    let frames = norm.frames;
    if opts.scale > 0.0 || opts.channel_scale > 0.0 {
        // The raw readings times k, in normalised units: k z + (k - 1) mean / std, per channel;
        // k one factor for the window times one of the channel's own.
        let window = if opts.scale > 0.0 { log_uniform_factor(opts.scale, rng) as f32 } else { 1.0 };
        for (row, (m, s)) in sample.chunks_mut(frames).zip(norm.mean.iter().zip(&norm.std)) {
            let own = if opts.channel_scale > 0.0 { log_uniform_factor(opts.channel_scale, rng) as f32 } else { 1.0 };
            let k = window * own;
            let lift = (k - 1.0) * m / s;
            row.iter_mut().for_each(|v| *v = k * *v + lift);
        }
    }
    if opts.vibration > 0.0 {
        // Each channel's variation about its mean over the window, times one factor for all.
        let k = log_uniform_factor(opts.vibration, rng) as f32;
        for row in sample.chunks_mut(frames) {
            let mean = row.iter().sum::<f32>() / frames as f32;
            row.iter_mut().for_each(|v| *v = mean + k * (*v - mean));
        }
    }
    if opts.shift > 0 {
        let span = 2 * opts.shift + 1;
        let shift = rng.below(span) as isize - opts.shift as isize;
        let last = frames as isize - 1;
        for row in sample.chunks_mut(frames) {
            let original = row.to_vec();
            for (t, v) in row.iter_mut().enumerate() {
                *v = original[(t as isize - shift).clamp(0, last) as usize];
            }
        }
    }
    if opts.reverse > 0.0 && f64::from(rng.uniform()) < opts.reverse {
        sample.chunks_mut(frames).for_each(|row| row.reverse());
    }
    if opts.translate > 0 {
        let mut offset = || rng.below(2 * opts.translate + 1) as isize - opts.translate as isize;
        let by = [offset(), offset()];
        let from = |at: usize, len: usize, by: isize| (at as isize - by).clamp(0, len as isize - 1) as usize;
        let [h, w, _] = grid;
        remap(sample, norm, grid, |y, x| (from(y, h, by[0]), from(x, w, by[1])));
    }
    if opts.flip > 0.0 {
        let mut draw = || f64::from(rng.uniform()) < opts.flip;
        let (rows, columns) = (draw(), draw());
        let mirror = |at: usize, len: usize, on: bool| if on { len - 1 - at } else { at };
        let [h, w, _] = grid;
        if rows || columns {
            remap(sample, norm, grid, |y, x| (mirror(y, h, rows), mirror(x, w, columns)));
        }
    }
    let gain = 1.0 + opts.gain as f32 * (2.0 * rng.uniform() - 1.0);
    gain_and_noise(sample, gain, opts.noise as f32, rng);
}

/// Values a noise part draws at the least: below it a window is drawn in one part.
const NOISE_PART: usize = 1 << 16;

/// `v · gain + noise · z` for every value `v`, `z` a normal drawn from `rng` value by value in
/// order (none where `noise` is 0). A camera's window holds millions of values, so its normals are
/// drawn in parts on rayon's threads, each from where it falls in the stream ([`Rng::ahead`]):
/// bit for bit what drawing them in order gives.
fn gain_and_noise(sample: &mut [f32], gain: f32, noise: f32, rng: &mut Rng) {
    if noise <= 0.0 {
        sample.iter_mut().for_each(|v| *v *= gain);
        return;
    }
    let start = rng.clone();
    let part = NOISE_PART.max(sample.len().div_ceil(rayon::current_num_threads()));
    sample.par_chunks_mut(part).enumerate().for_each(|(k, values)| {
        let mut rng = start.ahead(Rng::NORMAL_DRAWS * (k * part) as u64);
        values.iter_mut().for_each(|v| *v = *v * gain + noise * rng.normal());
    });
    *rng = start.ahead(Rng::NORMAL_DRAWS * sample.len() as u64);
}

/// Redraws the image of a normalised window (`grid` height × width × colours rows of
/// `norm.frames`): the pixel at row y, column x takes the raw reading of the pixel `from(y, x)`
/// in the same colour, normalised as its own.
fn remap(sample: &mut [f32], norm: &Normalization, [_, w, c]: [usize; 3], from: impl Fn(usize, usize) -> (usize, usize)) {
    let frames = norm.frames;
    let original = sample.to_vec();
    for (row, out) in sample.chunks_mut(frames).enumerate() {
        let (y, x) = from(row / (w * c), row / c % w);
        let source = (y * w + x) * c + row % c;
        let (ms, ss, md, sd) = (norm.mean[source], norm.std[source], norm.mean[row], norm.std[row]);
        for (v, z) in out.iter_mut().zip(&original[source * frames..(source + 1) * frames]) {
            *v = (z * ss + ms - md) / sd;
        }
    }
}

/// A random factor of an augmentation, log-uniform in [1 / (1 + spread), 1 + spread]: as likely
/// to halve as to double. One draw of `rng`.
pub fn log_uniform_factor(spread: f64, rng: &mut Rng) -> f64 {
    ((1.0 + spread).ln() * (2.0 * rng.uniform() as f64 - 1.0)).exp()
}

#[cfg(test)]
mod tests;
