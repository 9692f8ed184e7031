//! Multi-head self-attention with a channel-selection mask: one trainable value per q/k/v inner
//! channel, multiplied onto q, k and v alike, so a zero removes that channel from all three.
//!
//! Scaling an output channel of q, k or v is scaling a row of its weight, so the mask (and the
//! attention scale, for q) is applied to the small weight matrices rather than to the large
//! activations: the same function, a fraction of the memory traffic in training.

use candle_core::{Result, Tensor, D};
use candle_nn::{linear, Init, Linear, Module, VarBuilder};

use pvt3_spec::names;

use crate::Config;

#[derive(Clone, Debug)]
pub struct Attention {
    /// `[3 · inner, dim]`, rows q, then k, then v (no bias).
    qkv: Tensor,
    out: Linear,
    channel_mask: Tensor,
    heads: usize,
    dim_head: usize,
    scale: f64,
}

impl Attention {
    pub fn new(cfg: &Config, vb: VarBuilder) -> Result<Self> {
        let inner = cfg.inner_dim();
        Ok(Self {
            qkv: vb.pp(names::QKV).get_with_hints((3 * inner, cfg.dim), names::WEIGHT, candle_nn::init::DEFAULT_KAIMING_NORMAL)?,
            out: linear(inner, cfg.dim, vb.pp(names::OUT))?,
            channel_mask: vb.get_with_hints(inner, names::CHANNEL_MASK, Init::Const(1.0))?,
            heads: cfg.heads,
            dim_head: cfg.dim_head,
            scale: (cfg.dim_head as f64).powf(-0.5),
        })
    }

    /// `x`: `[sequences, tokens, dim]` → the same shape, times the dropout mask `drop` if given.
    pub fn forward(&self, x: &Tensor, drop: Option<&Tensor>) -> Result<Tensor> {
        let (b, l, d) = x.dims3()?;
        let inner = self.heads * self.dim_head;
        let rows = x.reshape((b * l, d))?;
        let mask = self.channel_mask.unsqueeze(1)?;
        let project = |i: usize, scale: f64| -> Result<Tensor> {
            let w = (self.qkv.narrow(0, i * inner, inner)?.broadcast_mul(&mask)? * scale)?;
            let y = rows.matmul(&w.t()?)?;
            if self.heads == 1 {
                y.reshape((b, l, inner))
            } else {
                y.reshape((b, l, self.heads, self.dim_head))?.transpose(1, 2)?.contiguous()
            }
        };
        let (q, k, v) = (project(0, self.scale)?, project(1, 1.0)?, project(2, 1.0)?);
        let probs = candle_nn::ops::softmax(&q.matmul(&k.t()?)?, D::Minus1)?;
        let mixed = probs.matmul(&v)?;
        let heads = if self.heads == 1 { mixed } else { mixed.transpose(1, 2)? };
        let heads = heads.reshape((b * l, inner))?;
        let out = self.out.forward(&heads)?.reshape((b, l, d))?;
        drop.map_or(Ok(out.clone()), |m| out * m)
    }
}
