//! What a training step minimises, term by term: the smoothed cross-entropy of the answers, and
//! in a joint run the distance between two networks' encodings of touches of the same class.

use candle_core::{Tensor, D};

use crate::Result;

/// Cross-entropy against labels smoothed by `eps`.
pub fn smoothed_cross_entropy(logits: &Tensor, labels: &Tensor, eps: f64) -> Result<Tensor> {
    let nll = candle_nn::loss::cross_entropy(logits, labels)?;
    if eps == 0.0 {
        return Ok(nll);
    }
    let uniform = candle_nn::ops::log_softmax(logits, D::Minus1)?.mean_all()?.neg()?;
    Ok(((nll * (1.0 - eps))? + (uniform * eps)?)?)
}

/// The mean squared error between two networks' encodings of paired touches (`--joint`).
pub fn encodings_apart(a: &Tensor, b: &Tensor) -> Result<Tensor> {
    Ok((a - b)?.sqr()?.mean_all()?)
}

#[cfg(test)]
mod tests {
    use candle_core::{Device, Tensor};

    #[test]
    fn smoothing_spreads_a_share_of_the_target_over_every_class() {
        let logits = Tensor::new(&[[2.0f32, 0.0, -1.0]], &Device::Cpu).unwrap();
        let labels = Tensor::new(&[0u32], &Device::Cpu).unwrap();
        let log_p: Vec<f32> = candle_nn::ops::log_softmax(&logits, 1).unwrap().flatten_all().unwrap().to_vec1().unwrap();
        let at = |eps: f64| super::smoothed_cross_entropy(&logits, &labels, eps).unwrap().to_scalar::<f32>().unwrap();
        assert!((at(0.0) + log_p[0]).abs() < 1e-6);
        let expected = -(0.9 * log_p[0] + 0.1 * log_p.iter().sum::<f32>() / 3.0);
        assert!((at(0.1) - expected).abs() < 1e-6, "{} against {expected}", at(0.1));
    }
}
