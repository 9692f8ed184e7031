//! A whole pre-norm transformer block, `x + Drop(Attn(LN(x)))` then `+ Drop(FFN(LN(·)))`, as one
//! candle op with a hand-written backward: candle's `CustomOp2` over the block's input and its
//! thirteen parameters packed into one vector (a `cat` whose backward hands each parameter its
//! share). Built from candle ops, a block is ~40 graph nodes whose backward allocates and
//! zero-fills a gradient buffer per node and reduces every broadcast; fused, it is one node.
//!
//! The op keeps the activations its backward needs when training (else the backward recomputes
//! them). The rows are cut into fixed chunks of whole sequences that run on rayon's threads; the
//! chunks do not depend on the thread count and their weight gradients are summed in chunk order,
//! so a run gives the same bits on one thread or many.

use std::ops::Range;
use std::sync::OnceLock;

use candle_core::backend::BackendStorage;
use candle_core::{CpuStorage, CustomOp2, Layout, Result, Shape, Tensor};
use rayon::prelude::*;

use crate::dense::axpy;

/// Rows per chunk of work at most: large enough for efficient matrix products, small enough that
/// a batch splits into several chunks for the threads.
const CHUNK_ROWS: usize = 512;
/// Chunks at least, where there are enough sequences: so that a few long sequences (the temporal
/// transformer's) still spread evenly over the threads.
const MIN_CHUNKS: usize = 8;
/// Activations a block keeps for its backward at most, in values (64 MB). Above, its backward
/// recomputes them, so that one block's are held at a time instead of every block's: a batch of
/// camera frames at full size (240 × 320 in patches of 40 × 40) would keep 0.6 GB over the
/// spatial transformer. A batch of tactile arrays, or of camera frames at 30 × 40, keeps fewer.
const KEEP_VALUES: usize = 1 << 24;

/// Defines the method `$name`, which runs `$body` compiled a second time for AVX2 (as `$avx2`)
/// where the CPU has it: the short loops of attention, the norms and the elementwise work, all
/// inlined into `$body`, then run on 8-lane vectors instead of SSE's 4. The same operations in the
/// same order (no fused multiply-add), so the same bits either way.
macro_rules! with_avx2 {
    ($(#[$doc:meta])* $vis:vis fn $name:ident / $avx2:ident => $body:ident($($arg:ident: $ty:ty),*) -> $ret:ty) => {
        $(#[$doc])*
        $vis fn $name(&self, $($arg: $ty),*) -> $ret {
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU has AVX2, checked just above.
                return unsafe { self.$avx2($($arg),*) };
            }
            self.$body($($arg),*)
        }

        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        unsafe fn $avx2(&self, $($arg: $ty),*) -> $ret {
            self.$body($($arg),*)
        }
    };
}

mod backward;
mod dropout;
mod forward;
mod layout;

pub use dropout::{BlockDropout, Masks};
pub use layout::BlockDims;
use layout::*;

/// One block applied to `[sequences, tokens, dim]`, with its backward; the output is the same
/// shape, or with `first_only` `[sequences, 1, dim]`: the first (CLS) token alone, which is all
/// that PVT³ reads of a transformer's last block. Every token's keys and values still feed it, but
/// the other tokens' attention, projection and feed-forward are skipped.
pub struct BlockOp {
    dims: BlockDims,
    dropout: Option<BlockDropout>,
    /// Keep the activations for the backward (training) instead of recomputing them there, where
    /// they are at most [`KEEP_VALUES`].
    keep: bool,
    first_only: bool,
    saved: OnceLock<Saved>,
}

struct Saved {
    tokens: usize,
    weights: Effective,
    chunks: Vec<Activations>,
}

/// What the backward needs of one chunk.
#[derive(Default)]
struct Activations {
    xhat1: Vec<f32>,
    rstd1: Vec<f32>,
    a: Vec<f32>,
    qkv: Vec<f32>,
    probs: Vec<f32>,
    heads: Vec<f32>,
    xhat2: Vec<f32>,
    rstd2: Vec<f32>,
    c: Vec<f32>,
    h: Vec<f32>,
    /// `Φ(h)`, the normal distribution function of the hidden units: GELU is `h · Φ(h)`.
    cdf: Vec<f32>,
    gd: Vec<f32>,
    masks: Option<Masks>,
}

/// The weights as the products use them: the channel masks and the attention scale folded in.
struct Effective {
    qkv: Vec<f32>,
    fc2: Vec<f32>,
}

impl BlockOp {
    pub fn new(dims: BlockDims, dropout: Option<BlockDropout>, keep: bool, first_only: bool) -> Self {
        Self { dims, dropout, keep, first_only, saved: OnceLock::new() }
    }

    /// The tokens of each sequence whose output is computed: all, or the first.
    fn queries(&self, tokens: usize) -> usize {
        if self.first_only {
            1
        } else {
            tokens
        }
    }

    /// Applies the block: `x` `[sequences, tokens, dim]`, `packed` the parameters of
    /// [`BlockDims::parameters`] flattened and concatenated.
    pub fn apply(self, x: &Tensor, packed: &Tensor) -> Result<Tensor> {
        x.contiguous()?.apply_op2(&packed.contiguous()?, self)
    }

    fn chunks(&self, sequences: usize, tokens: usize) -> Vec<Range<usize>> {
        let count = (sequences * tokens).div_ceil(CHUNK_ROWS).max(MIN_CHUNKS).min(sequences.max(1));
        let per = sequences.div_ceil(count).max(1);
        (0..sequences).step_by(per).map(|s| s..(s + per).min(sequences)).collect()
    }

    fn effective(&self, p: &[f32]) -> Effective {
        let (d, inner, r) = (self.dims.dim, self.dims.inner(), self.dims.ranges());
        let (w, mask) = (&p[r[QKV].clone()], &p[r[ATTN_MASK].clone()]);
        let mut qkv = vec![0f32; 3 * inner * d];
        for (row, (dst, src)) in qkv.chunks_exact_mut(d).zip(w.chunks_exact(d)).enumerate() {
            let scale = if row < inner { self.dims.scale } else { 1.0 };
            let m = mask[row % inner];
            for (o, v) in dst.iter_mut().zip(src) {
                *o = v * m * scale;
            }
        }
        let (w2, fmask) = (&p[r[FC2_W].clone()], &p[r[FFN_MASK].clone()]);
        let fc2 = w2.chunks_exact(self.dims.mlp).flat_map(|row| row.iter().zip(fmask).map(|(v, m)| v * m)).collect();
        Effective { qkv, fc2 }
    }

    fn check(&self, lx: &Layout, lp: &Layout) -> Result<(usize, usize)> {
        let (sequences, tokens, dim) = lx.shape().dims3()?;
        let want: usize = self.dims.ranges()[FFN_MASK].end;
        if dim != self.dims.dim || lp.shape().elem_count() != want {
            candle_core::bail!(
                "fused block: input {:?} and {} packed parameters for dim {} ({want} parameters)",
                lx.shape(),
                lp.shape().elem_count(),
                self.dims.dim
            );
        }
        Ok((sequences, tokens))
    }
}

/// Parameters flattened and concatenated into the one vector a fused op takes (a `cat`, whose
/// backward hands each parameter its share of the gradient).
pub fn pack<'a>(parts: impl IntoIterator<Item = &'a Tensor>) -> Result<Tensor> {
    let flat = parts.into_iter().map(|t| t.flatten_all()).collect::<Result<Vec<_>>>()?;
    Tensor::cat(&flat, 0)
}

/// The contiguous f32 values of a storage.
pub(crate) fn values<'a>(s: &'a CpuStorage, l: &Layout) -> Result<&'a [f32]> {
    match (s, l.contiguous_offsets()) {
        (CpuStorage::F32(v), Some((start, end))) => Ok(&v[start..end]),
        (CpuStorage::F32(_), None) => candle_core::bail!("fused op: a non-contiguous input"),
        _ => candle_core::bail!("fused op: f32 only, got {:?}", s.dtype()),
    }
}

impl CustomOp2 for BlockOp {
    fn name(&self) -> &'static str {
        "pvt3-fused-block"
    }

    fn cpu_fwd(&self, sx: &CpuStorage, lx: &Layout, sp: &CpuStorage, lp: &Layout) -> Result<(CpuStorage, Shape)> {
        let (sequences, tokens) = self.check(lx, lp)?;
        let (x, p) = (values(sx, lx)?, values(sp, lp)?);
        let weights = self.effective(p);
        let keep = self.keep && self.dims.activations(sequences, tokens, self.queries(tokens)) <= KEEP_VALUES;
        let (outputs, chunks): (Vec<Vec<f32>>, Vec<Activations>) =
            self.run_forward(x, p, &weights, sequences, tokens, keep).into_iter().unzip();
        if keep {
            // Set once: each application of the block is a fresh op.
            let _ = self.saved.set(Saved { tokens, weights, chunks });
        }
        Ok((CpuStorage::F32(outputs.concat()), Shape::from((sequences, self.queries(tokens), self.dims.dim))))
    }

    fn bwd(&self, x: &Tensor, packed: &Tensor, _res: &Tensor, grad: &Tensor) -> Result<(Option<Tensor>, Option<Tensor>)> {
        let (sequences, tokens, _) = x.dims3()?;
        let p = packed.flatten_all()?.to_vec1::<f32>()?;
        let dy = grad.flatten_all()?.to_vec1::<f32>()?;
        let recomputed;
        let (w, chunks) = match self.saved.get() {
            Some(saved) if saved.tokens == tokens => (&saved.weights, &saved.chunks),
            _ => {
                let xs = x.flatten_all()?.to_vec1::<f32>()?;
                let w = self.effective(&p);
                let chunks = self.run_forward(&xs, &p, &w, sequences, tokens, true).into_iter().map(|(_, a)| a).collect();
                recomputed = (w, chunks);
                (&recomputed.0, &recomputed.1)
            }
        };
        let row_len = self.queries(tokens) * self.dims.dim;
        let parts: Vec<(Vec<f32>, Vec<f32>)> = self
            .chunks(sequences, tokens)
            .into_par_iter()
            .zip(chunks.par_iter())
            .map(|(s, acts)| {
                let mut g = vec![0f32; p.len()];
                let dx = self.backward_chunk(&p, w, acts, &dy[s.start * row_len..s.end * row_len], tokens, &mut g);
                (dx, g)
            })
            .collect();
        let mut g = vec![0f32; p.len()];
        for (_, part) in &parts {
            axpy(&mut g, 1.0, part);
        }
        self.unfold_effective(&p, &mut g);
        let dx = parts.into_iter().map(|(dx, _)| dx).collect::<Vec<_>>().concat();
        Ok((Some(Tensor::from_vec(dx, x.shape(), x.device())?), Some(Tensor::from_vec(g, packed.shape(), packed.device())?)))
    }
}

/// Where head `sh % heads` of sequence `sh / heads` starts: its q, k and v in `qkv`
/// (`[rows, 3 · inner]`), and its output among the mixed values of the `queries` tokens of each
/// sequence whose output is computed (`[sequences · queries, inner]`).
#[inline(always)]
fn head_offsets(d: &BlockDims, tokens: usize, queries: usize, sh: usize) -> (usize, usize, usize, usize) {
    let (inner, s, h) = (d.inner(), sh / d.heads, (sh % d.heads) * d.dim_head);
    let qkv = s * tokens * 3 * inner + h;
    (qkv, qkv + inner, qkv + 2 * inner, s * queries * inner + h)
}

/// From this many tokens on, attention's products go through gemm; below, short loops are faster.
const GEMM_TOKENS: usize = 16;

#[cfg(test)]
mod tests;
