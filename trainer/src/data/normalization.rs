//! Fitting the per-channel normalisation on the training split only (the plain
//! [`Normalization`] it fills is the file contract's, in `pvt3-spec`, which the exporter writes
//! into the model).

pub use pvt3_spec::normalization::Normalization;

use crate::data::Dataset;

/// A channel whose training values barely vary (an idle taxel) keeps unit scale.
const MIN_STD: f64 = 1e-6;

/// Mean and standard deviation per channel over the `indices` touches and all their frames, for
/// a model reading windows of `window` frames.
pub fn fit(data: &Dataset, indices: &[usize], window: usize) -> Normalization {
    let frames = data.max_frames();
    let channels = data.sample_len() / frames;
    let mut sum = vec![0f64; channels];
    let mut sq = vec![0f64; channels];
    let mut count = 0;
    for &i in indices {
        let len = data.lengths[i];
        for (c, row) in data.sample(i).chunks(frames).enumerate() {
            sum[c] += row[..len].iter().map(|v| *v as f64).sum::<f64>();
            sq[c] += row[..len].iter().map(|v| (*v as f64).powi(2)).sum::<f64>();
        }
        count += len;
    }
    let count = count.max(1) as f64;
    let mean: Vec<f64> = sum.iter().map(|s| s / count).collect();
    let std = sq
        .iter()
        .zip(&mean)
        .map(|(s, m)| {
            let sd = (s / count - m * m).max(0.0).sqrt();
            if sd < MIN_STD {
                1.0
            } else {
                sd as f32
            }
        })
        .collect();
    Normalization { mean: mean.into_iter().map(|m| m as f32).collect(), std, frames: window }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_uses_only_the_given_samples_and_standardises_them() {
        // Two channels, three frames, three samples; sample 2 is an outlier left out of the fit.
        let x = vec![1., 2., 3., 0., 0., 0., 3., 4., 5., 0., 0., 0., 100., 100., 100., 9., 9., 9.];
        let data = Dataset::in_memory(x, vec![2, 1, 3], vec![0, 1, 0]);
        let norm = fit(&data, &[0, 1], 3);
        assert_eq!(norm.mean, vec![3.0, 0.0]);
        assert!((norm.std[0] - (10.0f32 / 6.0).sqrt()).abs() < 1e-6);
        assert_eq!(norm.std[1], 1.0, "a constant channel keeps unit scale");
        let mut out = Vec::new();
        norm.apply_into(&data.sample(1), &mut out);
        assert!((out[0]).abs() < 1e-6 && out[3..] == [0.0, 0.0, 0.0]);
    }
}
