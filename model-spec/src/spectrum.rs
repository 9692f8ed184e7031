//! The band maths of PVT³'s spectral head (`Config::spectral_bands() > 0`): which frequencies
//! each band sums, the real transform as a matrix, the band sums as a matrix, and which frames
//! the features read. The trainer's candle head (`pvt3_models::spectrum`), the f64 reference and
//! the exporter all read them here.
//!
//! The features stream: they are those of the frames a touch has delivered so far, of the kept
//! temporal tokens only. Frame `n` has weight `w_n`, 1 if its token is kept and received, else 0;
//! with `N = max(Σ w_n, 1)`, a channel's level is `Σ w_n x_n / N`, its transform
//! `X_f = Σ w_n (x_n − level) D[n, f]` ([`dft_matrix`]: the window's basis, zeros where `w` is),
//! and band `j`'s power `(T / N) Σ_{f ∈ j} X_f²`, so that a stationary signal has the same
//! expected power after any number of frames. With every frame kept and received, `N = T`: the
//! whole window's periodogram.

pub mod space;

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

/// The weight of each of `frames` frames (see the module's docs): 1 for a frame of a temporal
/// token (`tubelet` frames each) below `tokens` that `kept` keeps, 0 otherwise.
pub fn frame_weights(frames: usize, tubelet: usize, tokens: usize, kept: impl Fn(usize) -> bool) -> Vec<f64> {
    (0..frames).map(|n| if n / tubelet < tokens && kept(n / tubelet) { 1.0 } else { 0.0 }).collect()
}

/// `N` of the module's docs: the frames weighed, at least 1 (a touch with no kept frame yet has
/// level 0 and no power).
pub fn weighed_frames(weights: &[f64]) -> f64 {
    weights.iter().sum::<f64>().max(1.0)
}

/// `[frames, 2 · bins]` row-major: frame `n`'s `cos(2π k n / T) / √T` for each frequency `k`,
/// then its `sin`, so that a row vector of frames times it gives the transform's real and
/// (negated) imaginary parts, scaled so that white noise of unit variance has unit power.
pub fn dft_matrix(frames: usize) -> Vec<f64> {
    cos_sin_matrix(frames, bins(frames))
}

/// `[n, 2 · k]` row-major: value `m`'s `cos(2π f m / n) / √n` for each frequency `f < k`, then
/// its `sin` ([`dft_matrix`] of `k = bins(n)`; an image's axes in [`space`]).
pub fn cos_sin_matrix(n: usize, k: usize) -> Vec<f64> {
    let norm = (n as f64).sqrt();
    let mut m = vec![0.0; n * 2 * k];
    for i in 0..n {
        for f in 0..k {
            let angle = 2.0 * std::f64::consts::PI * ((f * i) % n) as f64 / n as f64;
            m[i * 2 * k + f] = angle.cos() / norm;
            m[i * 2 * k + k + f] = angle.sin() / norm;
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
}
