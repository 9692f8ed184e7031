//! Augmentation of training windows. Each window is changed alone as it is batched ([`augment`]:
//! a firmer or lighter press, a stronger or weaker vibration, a shift in time, the other sliding
//! direction, an image moved or mirrored, a gain and noise);
//! a batch as a whole is blended with itself ([`mixup`]) or pushed beyond its touches
//! ([`extrapolation`]) in the learner's forward pass.

pub mod extrapolation;
pub mod mixup;

use pvt3_models::Rng;
use rayon::prelude::*;

use super::normalization::Normalization;
use crate::options::Augmentation;

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
