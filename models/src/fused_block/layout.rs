//! The fused block's packed parameters: their sizes ([`BlockDims`]) and where each lies in the
//! one vector the op takes, in the order of `pvt3_spec::names::BLOCK`.

use std::ops::Range;

use pvt3_spec::names;

use crate::Config;

// The packed parameters, in the order of `pvt3_spec::names::BLOCK` (names under the block's
// variable prefix).
pub(super) const LN1_W: usize = 0;
pub(super) const LN1_B: usize = 1;
pub(super) const QKV: usize = 2;
pub(super) const ATTN_MASK: usize = 3;
pub(super) const OUT_W: usize = 4;
pub(super) const OUT_B: usize = 5;
pub(super) const LN2_W: usize = 6;
pub(super) const LN2_B: usize = 7;
pub(super) const FC1_W: usize = 8;
pub(super) const FC1_B: usize = 9;
pub(super) const FC2_W: usize = 10;
pub(super) const FC2_B: usize = 11;
pub(super) const FFN_MASK: usize = 12;

/// The sizes of a block, from the model's configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlockDims {
    pub dim: usize,
    pub heads: usize,
    pub dim_head: usize,
    pub mlp: usize,
    pub eps: f32,
    /// The attention scale, `dim_head^-0.5`, folded into the q weights.
    pub scale: f32,
}

impl BlockDims {
    pub fn new(cfg: &Config) -> Self {
        Self {
            dim: cfg.dim,
            heads: cfg.heads,
            dim_head: cfg.dim_head,
            mlp: cfg.mlp_dim,
            eps: cfg.layer_norm_eps as f32,
            scale: (cfg.dim_head as f64).powf(-0.5) as f32,
        }
    }

    pub(super) fn inner(&self) -> usize {
        self.heads * self.dim_head
    }

    /// The values of the activations a block's forward keeps for its backward
    /// ([`super::Activations`]), over `sequences` of `tokens`, `queries` of which are computed.
    pub(super) fn activations(&self, sequences: usize, tokens: usize, queries: usize) -> usize {
        let (rows, out_rows) = (sequences * tokens, sequences * queries);
        let (d, inner) = (self.dim, self.inner());
        rows * (2 * d + 1 + 3 * inner) + out_rows * (self.heads * tokens + inner + 2 * d + 1 + 3 * self.mlp)
    }

    /// Each packed parameter's name (under the block's prefix) and shape, in packing order.
    pub fn parameters(&self) -> [(String, Vec<usize>); 13] {
        names::BLOCK.map(|(path, shape)| (names::join(path), shape.iter().map(|s| s.of(self.dim, self.inner(), self.mlp)).collect()))
    }

    /// Where each parameter lies in the packed vector.
    pub(super) fn ranges(&self) -> [Range<usize>; 13] {
        let mut start = 0;
        self.parameters().map(|(_, shape)| {
            let len: usize = shape.iter().product();
            start += len;
            start - len..start
        })
    }
}
