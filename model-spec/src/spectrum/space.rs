//! The band maths of the spectral head over an image (`Pvt3Config::spectral_space`): what a
//! camera's texture is, wherever on the gel it is pressed. A frame's power spectrum does not move
//! when the imprint does, so the head reads, for each colour of each frame, the mean power of
//! `bands` rings of spatial frequency (geometrically spaced radii, the zero frequency left out),
//! beside the colour's mean level, and averages them over the kept frames received so far as the
//! temporal head does (`super`'s docs: the weights `w_n` and `N`). The trainer's candle head,
//! the f64 reference and the exporter all read these matrices.
//!
//! A frame `v[y, x]` of `h × w` has the transform `F(ky, kx) = Σ v[y, x] e^{−2πi (ky y / h +
//! kx x / w)} / √(h w)` (white noise of unit variance has unit power), read one-sided in `x`:
//! `ky < h`, `kx ≤ w / 2`. Frequency `(ky, kx)` has the radius `√((fy / h)² + (kx / w)²)`, `fy`
//! the signed frequency of `ky`. A band's power is the mean `|F|²` of the frequencies in it.
//!
//! Beside them, with `spectral_histogram` bins, the head reads each colour's histogram of the
//! frame's normalised values ([`histogram_matrix`]): the share of the gel a touch presses, and
//! how far, wherever it lies. Its bins are soft, so that it is continuous in the values and the
//! f32 forms equal the f64 reference. With `spectral_gradients`, it reads with the same bins the
//! histograms of the differences between neighbouring values across and down ([`Histogram`]):
//! how steep the imprint's slopes are and which way they face.
//!
//! A model whose patch mask pruned patches has the head read the frame with their pixels at 0,
//! the normalised training mean ([`kept_pixels`]): no form reads a pruned patch's pixels, and the
//! trainer fits the head again to what it then reads.

pub use super::cos_sin_matrix;
use crate::{Config, Error, Result};

/// Columns `kx` of the one-sided transform of a row of `width` values.
pub fn width_bins(width: usize) -> usize {
    width / 2 + 1
}

/// Whether a head over the image's space reads each pixel `[y · w + x]` of a frame of a model
/// that keeps `kept` patches (row-major over the grid): those of a kept patch. It reads every
/// other pixel as 0.
pub fn kept_pixels(c: &Config, kept: &[usize]) -> Vec<bool> {
    let (ph, pw, gw) = (c.patch_height, c.patch_width, c.width / c.patch_width);
    let mut of = vec![false; c.num_patches()];
    kept.iter().for_each(|p| of[*p] = true);
    (0..c.height).flat_map(|y| (0..c.width).map(move |x| (y, x))).map(|(y, x)| of[(y / ph) * gw + x / pw]).collect()
}

/// The radius of frequency `(ky, kx)` of an `h × w` frame.
pub fn radius(h: usize, w: usize, ky: usize, kx: usize) -> f64 {
    let fy = if ky <= h / 2 { ky as f64 } else { ky as f64 - h as f64 };
    ((fy / h as f64).powi(2) + (kx as f64 / w as f64).powi(2)).sqrt()
}

/// The band of each frequency, `[ky][kx]` row-major over `h × width_bins(w)`: `None` for the zero
/// frequency (the level's), else `j` of the `bands` rings whose radii `e_j = r₀ (r₁ / r₀)^(j /
/// bands)` run from the lowest radius, `r₀ = 1 / max(h, w)`, to the highest, `r₁`, each ring
/// `[e_j, e_{j+1})` and the last closed. Fails if a ring holds no frequency (too many bands for
/// so small a frame).
pub fn band_of(h: usize, w: usize, bands: usize) -> Result<Vec<Option<usize>>> {
    let k = width_bins(w);
    let top = (0..h).flat_map(|ky| (0..k).map(move |kx| radius(h, w, ky, kx))).fold(0.0, f64::max);
    let low = 1.0 / h.max(w) as f64;
    let edge = |j: usize| low * (top / low).powf(j as f64 / bands as f64);
    let of = |r: f64| -> Option<usize> {
        if r < low * (1.0 - 1e-9) {
            return None;
        }
        Some((0..bands).find(|&j| r < edge(j + 1) * (1.0 - 1e-12)).unwrap_or(bands - 1))
    };
    let found: Vec<Option<usize>> = (0..h).flat_map(|ky| (0..k).map(move |kx| (ky, kx))).map(|(ky, kx)| of(radius(h, w, ky, kx))).collect();
    if let Some(j) = (0..bands).find(|j| !found.contains(&Some(*j))) {
        return Err(Error::Config(format!(
            "spectral_bands = {bands}: ring {j} of a {h} × {w} frame's spatial spectrum holds no frequency; take fewer bands"
        )));
    }
    Ok(found)
}

/// Frequencies in each band.
pub fn band_sizes(of: &[Option<usize>], bands: usize) -> Vec<usize> {
    (0..bands).map(|j| of.iter().filter(|b| **b == Some(j)).count()).collect()
}

/// `[kx · h + ky, band]` row-major: `1 / size` where frequency `(ky, kx)` belongs to the band,
/// so that the powers laid out `[kx][ky]` (as a product with the width's matrix, then the
/// height's, leaves them) times it are the bands' mean powers.
pub fn ring_means(h: usize, w: usize, bands: usize) -> Result<Vec<f64>> {
    let k = width_bins(w);
    let of = band_of(h, w, bands)?;
    let sizes = band_sizes(&of, bands);
    let mut m = vec![0.0; k * h * bands];
    for ky in 0..h {
        for kx in 0..k {
            if let Some(j) = of[ky * k + kx] {
                m[(kx * h + ky) * bands + j] = 1.0 / sizes[j] as f64;
            }
        }
    }
    Ok(m)
}

/// What a head over the image's space takes a histogram of, in each colour of each frame, in
/// the order its features read them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Histogram {
    /// The normalised values `v[y, x]`.
    Values,
    /// The differences across, `v[y, x + 1] − v[y, x]`.
    Across,
    /// The differences down, `v[y + 1, x] − v[y, x]`.
    Down,
}

impl Histogram {
    /// The values' histogram and the gradients'.
    pub const ALL: [Histogram; 3] = [Histogram::Values, Histogram::Across, Histogram::Down];

    /// Rows and columns of what it reads of an `h × w` frame.
    pub fn shape(self, h: usize, w: usize) -> (usize, usize) {
        match self {
            Histogram::Values => (h, w),
            Histogram::Across => (h, w - 1),
            Histogram::Down => (h - 1, w),
        }
    }

    /// How many values it reads of an `h × w` frame.
    pub fn values(self, h: usize, w: usize) -> usize {
        let (rows, columns) = self.shape(h, w);
        rows * columns
    }

    /// Its value at `(y, x)` of [`Histogram::shape`] from the frame's values `v(y, x)`.
    pub fn at(self, v: impl Fn(usize, usize) -> f64, y: usize, x: usize) -> f64 {
        match self {
            Histogram::Values => v(y, x),
            Histogram::Across => v(y, x + 1) - v(y, x),
            Histogram::Down => v(y + 1, x) - v(y, x),
        }
    }
}

/// Half the histogram's range, in the normalised values' units (a pixel's standard deviations
/// over the training frames). PhysiCLeAR read best over ±3 of ±2 … ±6 (docs/camera.md).
pub const HISTOGRAM_RANGE: f64 = 3.0;

/// The width `Δ = 2 R / bins` of each of `bins` bins over `[−R, R]`, `R` = [`HISTOGRAM_RANGE`].
pub fn histogram_width(bins: usize) -> f64 {
    2.0 * HISTOGRAM_RANGE / bins as f64
}

/// The interior edges `e_j = −R + j Δ`, `j = 1 … bins − 1`.
pub fn histogram_edges(bins: usize) -> Vec<f64> {
    (1..bins).map(|j| -HISTOGRAM_RANGE + j as f64 * histogram_width(bins)).collect()
}

/// The share of a value `v` above `edge`: `clamp((v − edge) / Δ + ½, 0, 1)`, so that a value
/// within `Δ / 2` of an edge is shared linearly between the bins beside it (a bin's share of `v`
/// is a triangle of half-width Δ about its centre; the outer two also hold the tails).
pub fn share_above(v: f64, edge: f64, width: f64) -> f64 {
    ((v - edge) / width + 0.5).clamp(0.0, 1.0)
}

/// `[bins − 1, bins]` row-major and `[bins]`: the bins' shares `h = c · D + first` from the mean
/// shares `c_j` above the interior edges ([`share_above`]): `h_0 = 1 − c_1`, `h_j = c_j − c_{j+1}`,
/// `h_{bins−1} = c_{bins−1}`. The shares sum to one.
pub fn histogram_matrix(bins: usize) -> (Vec<f64>, Vec<f64>) {
    let mut d = vec![0.0; (bins - 1) * bins];
    // Interior edge j (row j) is bin j's upper edge and bin j + 1's lower one.
    for j in 0..bins - 1 {
        d[j * bins + j] = -1.0;
        d[j * bins + j + 1] = 1.0;
    }
    let first = (0..bins).map(|j| if j == 0 { 1.0 } else { 0.0 }).collect();
    (d, first)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The matrix form of the histogram is its definition: each bin's share of a value is its
    /// share above the bin's lower edge less its share above the upper one, and the shares of a
    /// value sum to one, wherever it lies.
    #[test]
    fn the_histogram_s_matrix_is_its_definition() {
        let bins = 6;
        let (d, first) = histogram_matrix(bins);
        let (edges, width) = (histogram_edges(bins), histogram_width(bins));
        for v in [-9.0, -3.0, -2.6, -0.3, 0.0, 0.49, 1.2, 2.99, 7.0] {
            let c: Vec<f64> = edges.iter().map(|e| share_above(v, *e, width)).collect();
            let h: Vec<f64> = (0..bins).map(|j| first[j] + (0..bins - 1).map(|i| c[i] * d[i * bins + j]).sum::<f64>()).collect();
            let lower = |j: usize| if j == 0 { 1.0 } else { share_above(v, edges[j - 1], width) };
            let upper = |j: usize| if j == bins - 1 { 0.0 } else { share_above(v, edges[j], width) };
            for (j, hj) in h.iter().enumerate() {
                assert!((hj - (lower(j) - upper(j))).abs() < 1e-12, "{v}: bin {j}");
                assert!((0.0..=1.0).contains(hj), "{v}: bin {j} = {hj}");
            }
            assert!((h.iter().sum::<f64>() - 1.0).abs() < 1e-12, "{v}: {h:?}");
        }
        // A value at a bin's centre is that bin's alone; one at an edge is shared half and half.
        let centre = -HISTOGRAM_RANGE + 2.5 * width;
        assert_eq!(edges.iter().map(|e| share_above(centre, *e, width)).collect::<Vec<_>>(), vec![1.0, 1.0, 0.0, 0.0, 0.0]);
        assert_eq!(share_above(edges[2], edges[2], width), 0.5);
    }

    /// Every frequency but the zero one lies in exactly one band, and no band is empty, at the
    /// sizes a camera is imported at; too many bands for a small frame is an error.
    #[test]
    fn the_rings_tile_the_frequencies_above_zero() {
        for (h, w, bands) in [(30, 40, 12), (60, 80, 16), (16, 16, 8), (240, 320, 16), (31, 17, 6)] {
            let of = band_of(h, w, bands).unwrap();
            assert_eq!(of.len(), h * width_bins(w));
            assert_eq!(of[0], None, "{h} × {w}: the zero frequency is the level's");
            assert!(of[1..].iter().all(Option::is_some), "{h} × {w}");
            assert!(band_sizes(&of, bands).iter().all(|n| *n > 0));
            // The rings grow outward: a higher band never holds a lower radius.
            let mut by_band = vec![(f64::MAX, 0.0f64); bands];
            for ky in 0..h {
                for kx in 0..width_bins(w) {
                    if let Some(j) = of[ky * width_bins(w) + kx] {
                        let r = radius(h, w, ky, kx);
                        by_band[j] = (by_band[j].0.min(r), by_band[j].1.max(r));
                    }
                }
            }
            assert!(by_band.windows(2).all(|p| p[0].1 <= p[1].0), "{h} × {w}: {by_band:?}");
        }
        assert!(band_of(16, 16, 40).is_err());
    }

    /// A pruned patch's pixels, and only they, are not read: at 30 × 40 with patches of 10 × 10
    /// (a grid of 3 × 4), keeping patches 1 and 6 reads columns 10 to 19 of rows 0 to 9 and
    /// columns 20 to 29 of rows 10 to 19.
    #[test]
    fn the_kept_pixels_are_the_kept_patches() {
        let c = Config::for_sensor(crate::Sensor::Camera, &[30, 40, 3, 25]).unwrap();
        assert_eq!((c.patch_height, c.patch_width), (10, 10));
        let kept = kept_pixels(&c, &[1, 6]);
        let at = |y: usize, x: usize| (y < 10 && (10..20).contains(&x)) || ((10..20).contains(&y) && (20..30).contains(&x));
        assert_eq!(kept, (0..30).flat_map(|y| (0..40).map(move |x| at(y, x))).collect::<Vec<_>>());
        assert!(kept_pixels(&c, &(0..12).collect::<Vec<_>>()).iter().all(|k| *k));
    }

    /// The transform's matrix is the definition's: a cosine of frequency 3 over 8 values gives
    /// √8 / 2 at frequency 3's real part and nothing else.
    #[test]
    fn the_matrix_transforms() {
        let m = cos_sin_matrix(8, 5);
        let row: Vec<f64> = (0..8).map(|i| (2.0 * std::f64::consts::PI * 3.0 * i as f64 / 8.0).cos()).collect();
        let out: Vec<f64> = (0..10).map(|f| (0..8).map(|i| row[i] * m[i * 10 + f]).sum()).collect();
        for (f, v) in out.iter().enumerate() {
            let want = if f == 3 { 8f64.sqrt() / 2.0 } else { 0.0 };
            assert!((v - want).abs() < 1e-12, "{f}: {v}");
        }
    }
}
