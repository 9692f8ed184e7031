//! The feed-forward block, `Linear → GELU (erf form) → × channel mask → Linear`, whose mask has
//! one trainable value per hidden unit.

use candle_core::{Result, Tensor};
use candle_nn::{linear, Init, Linear, Module, VarBuilder};

use crate::dropout::Dropout;
use crate::{Config, Rng};

#[derive(Clone, Debug)]
pub struct FeedForward {
    fc1: Linear,
    fc2: Linear,
    channel_mask: Tensor,
    dropout: Dropout,
}

impl FeedForward {
    pub fn new(cfg: &Config, vb: VarBuilder) -> Result<Self> {
        Ok(Self {
            fc1: linear(cfg.dim, cfg.mlp_dim, vb.pp("fc1"))?,
            fc2: linear(cfg.mlp_dim, cfg.dim, vb.pp("fc2"))?,
            channel_mask: vb.get_with_hints(cfg.mlp_dim, "channel_mask", Init::Const(1.0))?,
            dropout: Dropout::new(cfg.dropout),
        })
    }

    /// `x`: `[rows, dim]` → `[rows, dim]`.
    pub fn forward(&self, x: &Tensor, mut rng: Option<&mut Rng>) -> Result<Tensor> {
        let hidden = self.fc1.forward(x)?.gelu_erf()?.broadcast_mul(&self.channel_mask)?;
        let hidden = self.dropout.forward(&hidden, rng.as_deref_mut())?;
        self.dropout.forward(&self.fc2.forward(&hidden)?, rng)
    }
}
