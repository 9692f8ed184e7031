//! Same-class extrapolation (DeVries and Taylor, 2017): each training sample is pushed away from
//! another sample of its class in the batch, `x + λ (x − x_p)` with `λ ~ U(0, L)` per sample, and
//! keeps its label (`--extrapolate L`). Where two touches of a material differ by how they were
//! made (a firmer press, a faster slide), the step from one to the other continues the way the
//! material's own readings move: a sample the training never had, beyond the touches it has.
//! With `levels` (`--extrapolate-levels`) only each channel's level, its mean over the window,
//! moves: the two touches' vibrations are not aligned in time, so their difference is noise that
//! a whole-window step would add to the sample.

use candle_core::{Device, Tensor};
use pvt3_models::Rng;

use crate::Result;

/// The batch `x` (samples along the first axis, labels `y`), each sample extrapolated away from a
/// partner of its class drawn from the batch by `up_to`; a sample alone of its class is kept.
/// With `levels`, the step is the difference of the two samples' means over the last axis (time),
/// the same at every frame.
pub fn extrapolate(x: &Tensor, y: &Tensor, up_to: f64, levels: bool, rng: &mut Rng) -> Result<Tensor> {
    let labels = y.to_vec1::<u32>()?;
    let mut partners = Vec::with_capacity(labels.len());
    let mut lambdas = Vec::with_capacity(labels.len());
    for (i, label) in labels.iter().enumerate() {
        let kin: Vec<u32> = (0..labels.len() as u32).filter(|&j| j as usize != i && labels[j as usize] == *label).collect();
        let (partner, lambda) = match kin.len() {
            0 => (i as u32, 0.0),
            n => (kin[rng.below(n)], up_to as f32 * rng.uniform()),
        };
        partners.push(partner);
        lambdas.push(lambda);
    }
    let mut shape = vec![1; x.rank()];
    shape[0] = labels.len();
    let lambdas = Tensor::from_vec(lambdas, shape, &Device::Cpu)?;
    let partners = Tensor::new(partners.as_slice(), &Device::Cpu)?;
    let mut away = (x - x.index_select(&partners, 0)?)?;
    if levels {
        away = away.mean_keepdim(x.rank() - 1)?;
    }
    Ok(x.broadcast_add(&away.broadcast_mul(&lambdas)?)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_sample_moves_away_from_one_of_its_class_and_a_lone_sample_stays() {
        let mut rng = Rng::new(4);
        let x = Tensor::new(&[[1f32, 10.0], [3.0, 30.0], [5.0, 50.0], [7.0, 70.0]], &Device::Cpu).unwrap();
        let y = Tensor::new(&[0u32, 0, 1, 2], &Device::Cpu).unwrap();
        let got = extrapolate(&x, &y, 0.5, false, &mut rng).unwrap().to_vec2::<f32>().unwrap();
        // Samples 0 and 1 share a class: each goes beyond itself, away from the other, by λ ≤ 0.5
        // of their difference (2 in the first column), the same λ in every column.
        let (l0, l1) = ((1.0 - got[0][0]) / 2.0, (got[1][0] - 3.0) / 2.0);
        for l in [l0, l1] {
            assert!((0.0..=0.5).contains(&l), "λ {l}: {got:?}");
        }
        assert!((got[0][1] - (10.0 - 20.0 * l0)).abs() < 1e-4, "{got:?}");
        assert!((got[1][1] - (30.0 + 20.0 * l1)).abs() < 1e-4, "{got:?}");
        assert!(l0 > 0.0 && l1 > 0.0 && l0 != l1, "a λ of each sample's own: {got:?}");
        assert_eq!(&got[2..], &[[5.0, 50.0], [7.0, 70.0]], "alone of their class");
    }

    #[test]
    fn with_levels_only_the_mean_over_time_moves_and_the_variation_stays() {
        let x = Tensor::new(&[[[1f32, 3.0, 2.0]], [[10.0, 0.0, 20.0]], [[4.0, 4.0, 4.0]]], &Device::Cpu).unwrap();
        let y = Tensor::new(&[0u32, 0, 1], &Device::Cpu).unwrap();
        let got = extrapolate(&x, &y, 1.0, true, &mut Rng::new(9)).unwrap().to_vec3::<f32>().unwrap();
        // Means 2 and 10: sample 0 moves by -8 λ0 at every frame, sample 1 by +8 λ1.
        let (l0, l1) = ((1.0 - got[0][0][0]) / 8.0, (got[1][0][0] - 10.0) / 8.0);
        assert!((0.0..=1.0).contains(&l0) && (0.0..=1.0).contains(&l1) && l0 > 0.0 && l1 > 0.0, "{got:?}");
        for (t, (a, b)) in [(1.0, 10.0), (3.0, 0.0), (2.0, 20.0)].into_iter().enumerate() {
            assert!((got[0][0][t] - (a - 8.0 * l0)).abs() < 1e-4, "frame {t}: {got:?}");
            assert!((got[1][0][t] - (b + 8.0 * l1)).abs() < 1e-4, "frame {t}: {got:?}");
        }
        assert_eq!(got[2], [[4.0, 4.0, 4.0]], "alone of its class");
    }
}
