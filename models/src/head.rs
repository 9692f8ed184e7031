//! The classification head of the transformers (PVT³ and the ViT baseline): `LayerNorm → Linear`
//! on the CLS token's encoding, as the variables `head_norm.*` and `head.*`.

use candle_core::{Result, Tensor};
use candle_nn::{linear, Linear, Module, VarBuilder};

use crate::layer_norm::LayerNorm;
use pvt3_spec::names;

use crate::Config;

#[derive(Clone, Debug)]
pub struct Head {
    norm: LayerNorm,
    linear: Linear,
}

impl Head {
    /// `vb` is the model's root: the head's variables sit beside the model's own.
    pub fn new(cfg: &Config, vb: VarBuilder) -> Result<Self> {
        Ok(Self {
            norm: LayerNorm::new(cfg.dim, cfg.layer_norm_eps, vb.pp(names::HEAD_NORM))?,
            linear: linear(cfg.dim, cfg.classes, vb.pp(names::HEAD))?,
        })
    }

    /// `[b, dim]` → logits `[b, classes]`.
    pub fn forward(&self, cls: &Tensor) -> Result<Tensor> {
        self.linear.forward(&self.norm.forward(cls)?)
    }
}
