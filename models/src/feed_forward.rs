//! The feed-forward block, `Linear → GELU (erf form) → × channel mask → Linear`, whose mask has
//! one trainable value per hidden unit. Scaling a hidden unit is scaling the matching input
//! column of the second layer, so the mask is applied to that small weight matrix instead.

use candle_core::{Result, Tensor};
use candle_nn::{linear, Init, Linear, Module, VarBuilder};

use pvt3_spec::names;

use crate::Config;

#[derive(Clone, Debug)]
pub struct FeedForward {
    fc1: Linear,
    fc2_weight: Tensor,
    fc2_bias: Tensor,
    channel_mask: Tensor,
}

impl FeedForward {
    pub fn new(cfg: &Config, vb: VarBuilder) -> Result<Self> {
        let fc2 = linear(cfg.mlp_dim, cfg.dim, vb.pp(names::FC2))?;
        Ok(Self {
            fc1: linear(cfg.dim, cfg.mlp_dim, vb.pp(names::FC1))?,
            fc2_weight: fc2.weight().clone(),
            fc2_bias: fc2.bias().expect("linear has a bias").clone(),
            channel_mask: vb.get_with_hints(cfg.mlp_dim, names::CHANNEL_MASK, Init::Const(1.0))?,
        })
    }

    /// `x`: `[rows, dim]` → `[rows, dim]`, with the dropout masks `(hidden, out)` if given.
    pub fn forward(&self, x: &Tensor, drop: Option<(&Tensor, &Tensor)>) -> Result<Tensor> {
        let hidden = self.fc1.forward(x)?.gelu_erf()?;
        let hidden = drop.map_or(Ok(hidden.clone()), |(m, _)| hidden * m)?;
        let w2 = self.fc2_weight.broadcast_mul(&self.channel_mask.unsqueeze(0)?)?;
        let out = hidden.matmul(&w2.t()?)?.broadcast_add(&self.fc2_bias)?;
        drop.map_or(Ok(out.clone()), |(_, m)| out * m)
    }
}
