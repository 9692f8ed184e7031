//! A pre-norm transformer encoder, `x = x + Attn(LN(x)); x = x + FFN(LN(x))` per layer, with a
//! final layer norm. PVT³ only reads the CLS token out of it, so the last block computes that
//! token alone and the final norm is applied to it. Each block runs as one fused op with its own
//! backward ([`crate::fused_block`]); the composed form stays as the oracle of its tests and for
//! comparison.

use std::sync::atomic::{AtomicBool, Ordering};

use candle_core::{Result, Tensor};
use candle_nn::VarBuilder;

use pvt3_spec::names;

use crate::attention::Attention;
use crate::dropout::Dropout;
use crate::feed_forward::FeedForward;
use crate::fused_block::{pack, BlockDims, BlockDropout, BlockOp};
use crate::layer_norm::LayerNorm;
use crate::{Config, Rng};

static COMPOSED: AtomicBool = AtomicBool::new(false);

/// Runs the model composed of candle ops instead of the fused ops (every block and PVT³'s
/// embedding), process-wide: for measuring what the fusion gains (`pvt3 bench train --composed`).
/// The two compute the same function.
pub fn use_composed_ops(on: bool) {
    COMPOSED.store(on, Ordering::Relaxed);
}

pub(crate) fn composed_ops() -> bool {
    COMPOSED.load(Ordering::Relaxed)
}

#[derive(Clone, Debug)]
pub struct Block {
    attn_norm: LayerNorm,
    attn: Attention,
    ffn_norm: LayerNorm,
    ffn: FeedForward,
    /// The same variables in the fused op's packing order.
    packed: Vec<Tensor>,
    dims: BlockDims,
    dropout: Dropout,
}

impl Block {
    pub fn new(cfg: &Config, vb: VarBuilder) -> Result<Self> {
        let (attn_norm, attn) =
            (LayerNorm::new(cfg.dim, cfg.layer_norm_eps, vb.pp(names::ATTN_NORM))?, Attention::new(cfg, vb.pp(names::ATTN))?);
        let (ffn_norm, ffn) =
            (LayerNorm::new(cfg.dim, cfg.layer_norm_eps, vb.pp(names::FFN_NORM))?, FeedForward::new(cfg, vb.pp(names::FFN))?);
        let dims = BlockDims::new(cfg);
        // The modules above created the variables; these are the same ones, by name.
        let packed = dims.parameters().into_iter().map(|(name, shape)| vb.get(shape, &name)).collect::<Result<_>>()?;
        Ok(Self { attn_norm, attn, ffn_norm, ffn, packed, dims, dropout: Dropout::new(cfg.dropout) })
    }

    /// `x`: `[sequences, tokens, dim]` → the same shape, as one fused op (see [`BlockOp`]).
    pub fn forward(&self, x: &Tensor, rng: Option<&mut Rng>) -> Result<Tensor> {
        self.apply(x, rng, false)
    }

    /// The first (CLS) token's output alone, `[sequences, 1, dim]`: what a transformer's last
    /// block has to compute when only that token is read.
    pub fn forward_first(&self, x: &Tensor, rng: Option<&mut Rng>) -> Result<Tensor> {
        self.apply(x, rng, true)
    }

    fn apply(&self, x: &Tensor, rng: Option<&mut Rng>, first_only: bool) -> Result<Tensor> {
        let keep = rng.is_some();
        let dropout = self.draw_dropout(rng);
        if composed_ops() {
            let y = self.forward_composed(x, dropout.as_ref())?;
            return if first_only { y.narrow(1, 0, 1) } else { Ok(y) };
        }
        BlockOp::new(self.dims, dropout, keep, first_only).apply(x, &pack(&self.packed)?)
    }

    /// This step's dropout (one draw from `rng`), or `None` when evaluating or `p` is 0.
    pub fn draw_dropout(&self, rng: Option<&mut Rng>) -> Option<BlockDropout> {
        rng.filter(|_| self.dropout.p() > 0.0).map(|rng| BlockDropout { dropout: self.dropout.clone(), seed: rng.next_u64() })
    }

    /// The same block composed of candle ops, with the same dropout masks: the oracle the fused
    /// op is tested against, and what `pvt3 bench train --composed` times.
    pub fn forward_composed(&self, x: &Tensor, dropout: Option<&BlockDropout>) -> Result<Tensor> {
        let (b, l, d) = x.dims3()?;
        let masks = match dropout {
            Some(dropout) => {
                let m = dropout.masks(&self.dims, l, 0..b);
                let dev = x.device();
                Some((
                    Tensor::from_vec(m.attn, (b, l, d), dev)?,
                    Tensor::from_vec(m.hidden, (b * l, self.dims.mlp), dev)?,
                    Tensor::from_vec(m.out, (b * l, d), dev)?,
                ))
            }
            None => None,
        };
        let x = (x + self.attn.forward(&self.attn_norm.forward(x)?, masks.as_ref().map(|m| &m.0))?)?;
        let rows = self.ffn_norm.forward(&x.reshape((b * l, d))?)?;
        x + self.ffn.forward(&rows, masks.as_ref().map(|m| (&m.1, &m.2)))?.reshape((b, l, d))?
    }
}

#[derive(Clone, Debug)]
pub struct Transformer {
    layers: Vec<Block>,
    norm: LayerNorm,
}

impl Transformer {
    pub fn new(cfg: &Config, depth: usize, vb: VarBuilder) -> Result<Self> {
        let layers = (0..depth).map(|i| Block::new(cfg, vb.pp(names::LAYERS).pp(i))).collect::<Result<_>>()?;
        let norm = LayerNorm::new(cfg.dim, cfg.layer_norm_eps, vb.pp(names::NORM))?;
        Ok(Self { layers, norm })
    }

    /// `x`: `[sequences, tokens, dim]` → the normalised first (CLS) token, `[sequences, dim]`.
    pub fn forward_cls(&self, x: &Tensor, mut rng: Option<&mut Rng>) -> Result<Tensor> {
        let mut x = x.clone();
        for (i, layer) in self.layers.iter().enumerate() {
            // The last block computes the CLS token alone: nothing reads the others.
            x = if i + 1 == self.layers.len() {
                layer.forward_first(&x, rng.as_deref_mut())?
            } else {
                layer.forward(&x, rng.as_deref_mut())?
            };
        }
        self.norm.forward(&x.narrow(1, 0, 1)?.squeeze(1)?)
    }
}
