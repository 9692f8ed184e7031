//! A pre-norm transformer encoder, `x = x + Attn(LN(x)); x = x + FFN(LN(x))` per layer, with a
//! final layer norm. PVT³ only reads the CLS token out of it, so the final norm is applied to that
//! token alone.

use candle_core::{Result, Tensor};
use candle_nn::VarBuilder;

use crate::attention::Attention;
use crate::feed_forward::FeedForward;
use crate::layer_norm::LayerNorm;
use crate::{Config, Rng};

#[derive(Clone, Debug)]
pub struct Block {
    attn_norm: LayerNorm,
    attn: Attention,
    ffn_norm: LayerNorm,
    ffn: FeedForward,
}

impl Block {
    pub fn new(cfg: &Config, vb: VarBuilder) -> Result<Self> {
        Ok(Self {
            attn_norm: LayerNorm::new(cfg.dim, cfg.layer_norm_eps, vb.pp("attn_norm"))?,
            attn: Attention::new(cfg, vb.pp("attn"))?,
            ffn_norm: LayerNorm::new(cfg.dim, cfg.layer_norm_eps, vb.pp("ffn_norm"))?,
            ffn: FeedForward::new(cfg, vb.pp("ffn"))?,
        })
    }

    /// `x`: `[sequences, tokens, dim]` → the same shape.
    pub fn forward(&self, x: &Tensor, mut rng: Option<&mut Rng>) -> Result<Tensor> {
        let x = (x + self.attn.forward(&self.attn_norm.forward(x)?, rng.as_deref_mut())?)?;
        let (b, l, d) = x.dims3()?;
        let rows = self.ffn_norm.forward(&x.reshape((b * l, d))?)?;
        x + self.ffn.forward(&rows, rng)?.reshape((b, l, d))?
    }
}

#[derive(Clone, Debug)]
pub struct Transformer {
    layers: Vec<Block>,
    norm: LayerNorm,
}

impl Transformer {
    pub fn new(cfg: &Config, depth: usize, vb: VarBuilder) -> Result<Self> {
        let layers = (0..depth).map(|i| Block::new(cfg, vb.pp(format!("layers.{i}")))).collect::<Result<_>>()?;
        let norm = LayerNorm::new(cfg.dim, cfg.layer_norm_eps, vb.pp("norm"))?;
        Ok(Self { layers, norm })
    }

    /// `x`: `[sequences, tokens, dim]` → the normalised first (CLS) token, `[sequences, dim]`.
    pub fn forward_cls(&self, x: &Tensor, mut rng: Option<&mut Rng>) -> Result<Tensor> {
        let mut x = x.clone();
        for layer in &self.layers {
            x = layer.forward(&x, rng.as_deref_mut())?;
        }
        self.norm.forward(&x.narrow(1, 0, 1)?.squeeze(1)?)
    }
}
