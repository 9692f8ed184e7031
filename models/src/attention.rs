//! Multi-head self-attention with a channel-selection mask: one trainable value per q/k/v inner
//! channel, multiplied onto q, k and v alike, so a zero removes that channel from all three.

use candle_core::{Result, Tensor, D};
use candle_nn::{linear, linear_no_bias, Init, Linear, Module, VarBuilder};

use crate::dropout::Dropout;
use crate::{Config, Rng};

#[derive(Clone, Debug)]
pub struct Attention {
    qkv: Linear,
    out: Linear,
    channel_mask: Tensor,
    heads: usize,
    dim_head: usize,
    scale: f64,
    dropout: Dropout,
}

impl Attention {
    pub fn new(cfg: &Config, vb: VarBuilder) -> Result<Self> {
        let inner = cfg.inner_dim();
        Ok(Self {
            qkv: linear_no_bias(cfg.dim, 3 * inner, vb.pp("qkv"))?,
            out: linear(inner, cfg.dim, vb.pp("out"))?,
            channel_mask: vb.get_with_hints(inner, "channel_mask", Init::Const(1.0))?,
            heads: cfg.heads,
            dim_head: cfg.dim_head,
            scale: (cfg.dim_head as f64).powf(-0.5),
            dropout: Dropout::new(cfg.dropout),
        })
    }

    /// `x`: `[sequences, tokens, dim]` → the same shape.
    pub fn forward(&self, x: &Tensor, rng: Option<&mut Rng>) -> Result<Tensor> {
        let (b, l, d) = x.dims3()?;
        let inner = self.heads * self.dim_head;
        let mask = Tensor::cat(&[&self.channel_mask; 3], 0)?;
        let qkv = self.qkv.forward(&x.reshape((b * l, d))?)?.broadcast_mul(&mask)?;
        let split = |i: usize| -> Result<Tensor> {
            qkv.narrow(1, i * inner, inner)?
                .reshape((b, l, self.heads, self.dim_head))?
                .transpose(1, 2)?
                .contiguous()
        };
        let (q, k, v) = (split(0)?, split(1)?, split(2)?);
        let scores = (q.matmul(&k.t()?)? * self.scale)?;
        let probs = candle_nn::ops::softmax(&scores, D::Minus1)?;
        let heads = probs.matmul(&v)?.transpose(1, 2)?.reshape((b * l, inner))?;
        let out = self.out.forward(&heads)?.reshape((b, l, d))?;
        self.dropout.forward(&out, rng)
    }
}
