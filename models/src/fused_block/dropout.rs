//! The fused block's dropout: masks drawn per sequence, so that any split of the rows into
//! chunks draws the same ones.

use std::borrow::Cow;
use std::ops::Range;

use super::layout::BlockDims;
use crate::dropout::Dropout;
use crate::Rng;

/// One block's dropout in one training step. Its masks are drawn per sequence from `seed`, so
/// that the chunks draw them in parallel and any split of the rows gives the same masks.
#[derive(Clone, Debug)]
pub struct BlockDropout {
    pub dropout: Dropout,
    pub seed: u64,
}

/// The dropout masks of a run of sequences, each value 0 or `1 / (1 - p)`: the attention output
/// `[rows, dim]`, the feed-forward hidden units `[rows, mlp]` and its output `[rows, dim]`.
pub struct Masks {
    pub attn: Vec<f32>,
    pub hidden: Vec<f32>,
    pub out: Vec<f32>,
}

impl Masks {
    /// The masks of the first `queries` tokens of each sequence (all of them when `queries == tokens`).
    pub(super) fn first_rows(self, dims: &BlockDims, tokens: usize, queries: usize) -> Masks {
        if queries == tokens {
            return self;
        }
        let (d, h) = (dims.dim, dims.mlp);
        Masks {
            attn: first_rows(&self.attn, tokens * d, queries * d).into_owned(),
            hidden: first_rows(&self.hidden, tokens * h, queries * h).into_owned(),
            out: first_rows(&self.out, tokens * d, queries * d).into_owned(),
        }
    }
}

/// The first `keep` values of each `every`-long run of `values` (all of them, borrowed, when equal).
pub(super) fn first_rows(values: &[f32], every: usize, keep: usize) -> Cow<'_, [f32]> {
    if keep == every {
        return Cow::Borrowed(values);
    }
    Cow::Owned(values.chunks_exact(every).flat_map(|run| &run[..keep]).copied().collect())
}

/// The inverse of [`first_rows`]: each `keep`-long run of `values` at the start of an
/// `every`-long run of zeros.
pub(super) fn spread_first_rows(values: &[f32], every: usize, keep: usize) -> Vec<f32> {
    let mut out = vec![0f32; values.len() / keep * every];
    for (dst, src) in out.chunks_exact_mut(every).zip(values.chunks_exact(keep)) {
        dst[..keep].copy_from_slice(src);
    }
    out
}

impl BlockDropout {
    pub fn masks(&self, dims: &BlockDims, tokens: usize, sequences: Range<usize>) -> Masks {
        let (d, h) = (tokens * dims.dim, tokens * dims.mlp);
        let n = sequences.len();
        let mut m = Masks { attn: Vec::with_capacity(n * d), hidden: Vec::with_capacity(n * h), out: Vec::with_capacity(n * d) };
        for s in sequences {
            let mut rng = Rng::new(self.seed ^ (s as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
            for (values, len) in [(&mut m.attn, d), (&mut m.hidden, h), (&mut m.out, d)] {
                values.extend(self.dropout.mask(len, Some(&mut rng)).unwrap_or_else(|| vec![1.0; len]));
            }
        }
        m
    }
}
