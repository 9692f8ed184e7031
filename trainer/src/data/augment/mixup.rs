//! Mixup (Zhang et al., 2018): each training batch is blended with a shuffled copy of itself,
//! `λ x + (1 − λ) x[perm]`, with `λ ~ Beta(α, α)` drawn once per batch, and the loss is the same
//! blend of the two labels' losses (`--mixup ALPHA`). A regulariser for small data sets: the
//! network sees points between the training samples instead of the samples alone.

use candle_core::{Device, Tensor};
use pvt3_models::Rng;

use crate::Result;

/// A batch blended with its partners: the mixed input, the partners' labels and `λ`.
pub struct Mixed {
    pub x: Tensor,
    pub partner_labels: Tensor,
    pub lambda: f64,
}

/// Blends the batch `x` (samples along the first axis, labels `y`) with a shuffled copy of itself.
pub fn mix(x: &Tensor, y: &Tensor, alpha: f64, rng: &mut Rng) -> Result<Mixed> {
    let lambda = beta(alpha, rng);
    let mut partners: Vec<u32> = (0..x.dim(0)? as u32).collect();
    rng.shuffle(&mut partners);
    let partners = Tensor::new(partners.as_slice(), &Device::Cpu)?;
    let x = ((x * lambda)? + (x.index_select(&partners, 0)? * (1.0 - lambda))?)?;
    Ok(Mixed { x, partner_labels: y.index_select(&partners, 0)?, lambda })
}

/// A draw from Beta(α, α), as `g1 / (g1 + g2)` of two Gamma(α) draws.
fn beta(alpha: f64, rng: &mut Rng) -> f64 {
    let (a, b) = (gamma(alpha, rng), gamma(alpha, rng));
    if a + b > 0.0 {
        a / (a + b)
    } else {
        0.5
    }
}

/// A draw from Gamma(α, 1): Marsaglia and Tsang's method, with `Gamma(α + 1) · U^(1/α)` for α < 1.
fn gamma(alpha: f64, rng: &mut Rng) -> f64 {
    if alpha < 1.0 {
        let u = (rng.uniform() as f64).max(f64::MIN_POSITIVE);
        return gamma(alpha + 1.0, rng) * u.powf(1.0 / alpha);
    }
    let d = alpha - 1.0 / 3.0;
    let c = 1.0 / (9.0 * d).sqrt();
    loop {
        let z = rng.normal() as f64;
        let v = (1.0 + c * z).powi(3);
        if v <= 0.0 {
            continue;
        }
        let u = (rng.uniform() as f64).max(f64::MIN_POSITIVE);
        if u.ln() < 0.5 * z * z + d - d * v + d * v.ln() {
            return d * v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn beta_draws_have_the_right_mean_and_spread() {
        let mut rng = Rng::new(3);
        for alpha in [0.2, 1.0, 4.0] {
            let draws: Vec<f64> = (0..20_000).map(|_| beta(alpha, &mut rng)).collect();
            let mean = draws.iter().sum::<f64>() / draws.len() as f64;
            let var = draws.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / draws.len() as f64;
            // Beta(α, α): mean 1/2, variance 1 / (4 (2α + 1)).
            let want = 1.0 / (4.0 * (2.0 * alpha + 1.0));
            assert!((mean - 0.5).abs() < 0.01, "α {alpha}: mean {mean}");
            assert!((var - want).abs() < 0.05 * want, "α {alpha}: variance {var}, want {want}");
            assert!(draws.iter().all(|d| (0.0..=1.0).contains(d)));
        }
    }

    #[test]
    fn a_batch_is_blended_with_its_partners_and_their_labels() {
        let mut rng = Rng::new(9);
        let x = Tensor::new(&[[1f32, 1.0], [2.0, 2.0], [3.0, 3.0], [4.0, 4.0]], &Device::Cpu).unwrap();
        let y = Tensor::new(&[0u32, 1, 2, 3], &Device::Cpu).unwrap();
        let m = mix(&x, &y, 0.4, &mut rng).unwrap();
        let partners = m.partner_labels.to_vec1::<u32>().unwrap();
        let mut sorted = partners.clone();
        sorted.sort();
        assert_eq!(sorted, vec![0, 1, 2, 3], "a permutation of the batch");
        let got = m.x.to_vec2::<f32>().unwrap();
        for (i, row) in got.iter().enumerate() {
            let want = m.lambda * (i + 1) as f64 + (1.0 - m.lambda) * (partners[i] + 1) as f64;
            assert!(row.iter().all(|v| (*v as f64 - want).abs() < 1e-5), "row {i}: {row:?}, want {want}");
        }
    }
}
