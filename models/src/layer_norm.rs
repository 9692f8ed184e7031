//! Layer normalisation composed of differentiable tensor ops. candle-nn's fused layer-norm kernel
//! has no backward pass, so gradients would silently stop there during training.

use candle_core::{Result, Tensor, D};
use candle_nn::{Init, VarBuilder};
use pvt3_spec::names;

#[derive(Clone, Debug)]
pub struct LayerNorm {
    weight: Tensor,
    bias: Tensor,
    eps: f64,
}

impl LayerNorm {
    pub fn new(dim: usize, eps: f64, vb: VarBuilder) -> Result<Self> {
        let weight = vb.get_with_hints(dim, names::WEIGHT, Init::Const(1.0))?;
        let bias = vb.get_with_hints(dim, names::BIAS, Init::Const(0.0))?;
        Ok(Self { weight, bias, eps })
    }

    /// Normalises over the last dimension.
    pub fn forward(&self, x: &Tensor) -> Result<Tensor> {
        let centred = x.broadcast_sub(&x.mean_keepdim(D::Minus1)?)?;
        let var = centred.sqr()?.mean_keepdim(D::Minus1)?;
        let normed = centred.broadcast_div(&(var + self.eps)?.sqrt()?)?;
        normed.broadcast_mul(&self.weight)?.broadcast_add(&self.bias)
    }
}
