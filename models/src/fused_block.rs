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

use std::borrow::Cow;
use std::ops::Range;
use std::sync::OnceLock;

use candle_core::backend::BackendStorage;
use candle_core::{CpuStorage, CustomOp2, Layout, Result, Shape, Tensor};
use rayon::prelude::*;

use crate::dense::{add_column_sums, add_to_rows, axpy, dot, matmul, matmul_strided, product, View};
use crate::dropout::Dropout;
use crate::{Config, Rng};

/// Rows per chunk of work at most: large enough for efficient matrix products, small enough that
/// a batch splits into several chunks for the threads.
const CHUNK_ROWS: usize = 512;
/// Chunks at least, where there are enough sequences: so that a few long sequences (the temporal
/// transformer's) still spread evenly over the threads.
const MIN_CHUNKS: usize = 8;

// The packed parameters, in this order (names under the block's variable prefix).
const LN1_W: usize = 0;
const LN1_B: usize = 1;
const QKV: usize = 2;
const ATTN_MASK: usize = 3;
const OUT_W: usize = 4;
const OUT_B: usize = 5;
const LN2_W: usize = 6;
const LN2_B: usize = 7;
const FC1_W: usize = 8;
const FC1_B: usize = 9;
const FC2_W: usize = 10;
const FC2_B: usize = 11;
const FFN_MASK: usize = 12;
const NAMES: [&str; 13] = [
    "attn_norm.weight",
    "attn_norm.bias",
    "attn.qkv.weight",
    "attn.channel_mask",
    "attn.out.weight",
    "attn.out.bias",
    "ffn_norm.weight",
    "ffn_norm.bias",
    "ffn.fc1.weight",
    "ffn.fc1.bias",
    "ffn.fc2.weight",
    "ffn.fc2.bias",
    "ffn.channel_mask",
];

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

    fn inner(&self) -> usize {
        self.heads * self.dim_head
    }

    /// Each packed parameter's name and shape, in packing order.
    pub fn parameters(&self) -> [(&'static str, Vec<usize>); 13] {
        let (d, i, h) = (self.dim, self.inner(), self.mlp);
        let shapes = [
            vec![d],
            vec![d],
            vec![3 * i, d],
            vec![i],
            vec![d, i],
            vec![d],
            vec![d],
            vec![d],
            vec![h, d],
            vec![h],
            vec![d, h],
            vec![d],
            vec![h],
        ];
        std::array::from_fn(|i| (NAMES[i], shapes[i].clone()))
    }

    /// Where each parameter lies in the packed vector.
    fn ranges(&self) -> [Range<usize>; 13] {
        let mut start = 0;
        self.parameters().map(|(_, shape)| {
            let len: usize = shape.iter().product();
            start += len;
            start - len..start
        })
    }
}

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
    fn first_rows(self, dims: &BlockDims, tokens: usize, queries: usize) -> Masks {
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
fn first_rows(values: &[f32], every: usize, keep: usize) -> Cow<'_, [f32]> {
    if keep == every {
        return Cow::Borrowed(values);
    }
    Cow::Owned(values.chunks_exact(every).flat_map(|run| &run[..keep]).copied().collect())
}

/// The inverse of [`first_rows`]: each `keep`-long run of `values` at the start of an
/// `every`-long run of zeros.
fn spread_first_rows(values: &[f32], every: usize, keep: usize) -> Vec<f32> {
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

/// Defines the method `$name`, which runs `$body` compiled a second time for AVX2 (as `$avx2`)
/// where the CPU has it: the short loops of attention, the norms and the elementwise work, all
/// inlined into `$body`, then run on 8-lane vectors instead of SSE's 4. The same operations in the
/// same order (no fused multiply-add), so the same bits either way.
macro_rules! with_avx2 {
    ($(#[$doc:meta])* fn $name:ident / $avx2:ident => $body:ident($($arg:ident: $ty:ty),*) -> $ret:ty) => {
        $(#[$doc])*
        fn $name(&self, $($arg: $ty),*) -> $ret {
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

/// One block applied to `[sequences, tokens, dim]`, with its backward; the output is the same
/// shape, or with `first_only` `[sequences, 1, dim]`: the first (CLS) token alone, which is all
/// that PVT³ reads of a transformer's last block. Every token's keys and values still feed it, but
/// the other tokens' attention, projection and feed-forward are skipped.
pub struct BlockOp {
    dims: BlockDims,
    dropout: Option<BlockDropout>,
    /// Keep the activations for the backward (training) instead of recomputing them there.
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

    /// The forward pass of every chunk, in parallel: outputs and (if kept) activations.
    fn run_forward(
        &self,
        x: &[f32],
        p: &[f32],
        w: &Effective,
        sequences: usize,
        tokens: usize,
        keep: bool,
    ) -> Vec<(Vec<f32>, Activations)> {
        let row_len = tokens * self.dims.dim;
        self.chunks(sequences, tokens)
            .into_par_iter()
            .map(|s| self.forward_chunk(p, w, &x[s.start * row_len..s.end * row_len], s, tokens, keep))
            .collect()
    }

    with_avx2! {
        /// The forward pass of one chunk of sequences: its output and (if kept) activations.
        fn forward_chunk / forward_chunk_avx2 => forward_chunk_body(p: &[f32], w: &Effective, x: &[f32], sequences: Range<usize>, tokens: usize, keep: bool) -> (Vec<f32>, Activations)
    }

    #[inline(always)]
    fn forward_chunk_body(
        &self,
        p: &[f32],
        w: &Effective,
        x: &[f32],
        sequences: Range<usize>,
        tokens: usize,
        keep: bool,
    ) -> (Vec<f32>, Activations) {
        let d = &self.dims;
        let r = d.ranges();
        let (dim, inner, mlp) = (d.dim, d.inner(), d.mlp);
        let (rows, queries) = (x.len() / dim, self.queries(tokens));
        // The rows whose output is computed (all, or each sequence's first) and their masks.
        let out_rows = rows / tokens * queries;
        let masks = self.dropout.as_ref().map(|m| m.masks(d, tokens, sequences).first_rows(d, tokens, queries));
        let drop = masks.as_ref();
        let residual = first_rows(x, tokens * dim, queries * dim);

        let (mut xhat1, mut a, mut rstd1) = (vec![0f32; rows * dim], vec![0f32; rows * dim], vec![0f32; rows]);
        norm_rows(x, &p[r[LN1_W].clone()], &p[r[LN1_B].clone()], d.eps, &mut xhat1, &mut a, &mut rstd1);
        let qkv = product(View::rows(&a, rows, dim), View::rows(&w.qkv, 3 * inner, dim).t());
        let mut probs = vec![0f32; out_rows * d.heads * tokens];
        let mut heads = vec![0f32; out_rows * inner];
        attend(d, tokens, queries, &qkv, &mut probs, &mut heads);
        let rows = out_rows;
        let mut out = product(View::rows(&heads, rows, inner), View::rows(&p[r[OUT_W].clone()], dim, inner).t());
        add_bias_dropout_residual(&mut out, &p[r[OUT_B].clone()], drop.map(|m| &m.attn[..]), &residual);

        let (mut xhat2, mut c, mut rstd2) = (vec![0f32; rows * dim], vec![0f32; rows * dim], vec![0f32; rows]);
        norm_rows(&out, &p[r[LN2_W].clone()], &p[r[LN2_B].clone()], d.eps, &mut xhat2, &mut c, &mut rstd2);
        let mut h = product(View::rows(&c, rows, dim), View::rows(&p[r[FC1_W].clone()], mlp, dim).t());
        add_to_rows(&mut h, &p[r[FC1_B].clone()]);
        let cdf: Vec<f32> = h.iter().map(|&v| normal_cdf(v)).collect();
        let mut gd: Vec<f32> = h.iter().zip(&cdf).map(|(v, c)| v * c).collect();
        if let Some(m) = drop {
            gd.iter_mut().zip(&m.hidden).for_each(|(v, m)| *v *= m);
        }
        let mut f = product(View::rows(&gd, rows, mlp), View::rows(&w.fc2, dim, mlp).t());
        add_bias_dropout_residual(&mut f, &p[r[FC2_B].clone()], drop.map(|m| &m.out[..]), &out);

        let acts = if keep {
            Activations { xhat1, rstd1, a, qkv, probs, heads, xhat2, rstd2, c, h, cdf, gd, masks }
        } else {
            Activations::default()
        };
        (f, acts)
    }

    with_avx2! {
        /// The backward pass of one chunk: the input's gradient, and into `g` (laid out as the
        /// packed parameters) the gradients of the effective q/k/v and second-layer weights, the
        /// others as they are.
        fn backward_chunk / backward_chunk_avx2 => backward_chunk_body(p: &[f32], w: &Effective, acts: &Activations, dy: &[f32], tokens: usize, g: &mut [f32]) -> Vec<f32>
    }

    #[inline(always)]
    fn backward_chunk_body(&self, p: &[f32], w: &Effective, acts: &Activations, dy: &[f32], tokens: usize, g: &mut [f32]) -> Vec<f32> {
        let d = &self.dims;
        let r = d.ranges();
        let (dim, inner, mlp) = (d.dim, d.inner(), d.mlp);
        // `rows`: those whose output was computed; `all`: every token's.
        let (rows, queries) = (dy.len() / dim, self.queries(tokens));
        let all = rows / queries * tokens;
        let drop = acts.masks.as_ref();

        // Feed-forward.
        let mut df = dy.to_vec();
        if let Some(m) = drop {
            df.iter_mut().zip(&m.out).for_each(|(v, m)| *v *= m);
        }
        add_column_sums(&mut g[r[FC2_B].clone()], &df);
        matmul(&mut g[r[FC2_W].clone()], View::rows(&df, rows, dim).t(), View::rows(&acts.gd, rows, mlp), true);
        let mut dh = product(View::rows(&df, rows, dim), View::rows(&w.fc2, dim, mlp));
        let slopes = acts.h.iter().zip(&acts.cdf).map(|(&h, &cdf)| gelu_derivative(h, cdf));
        match drop {
            Some(m) => dh.iter_mut().zip(slopes.zip(&m.hidden)).for_each(|(v, (s, m))| *v *= s * m),
            None => dh.iter_mut().zip(slopes).for_each(|(v, s)| *v *= s),
        }
        add_column_sums(&mut g[r[FC1_B].clone()], &dh);
        matmul(&mut g[r[FC1_W].clone()], View::rows(&dh, rows, mlp).t(), View::rows(&acts.c, rows, dim), true);
        let dc = product(View::rows(&dh, rows, mlp), View::rows(&p[r[FC1_W].clone()], mlp, dim));
        let mut dx = dy.to_vec();
        norm_rows_backward(&dc, &acts.xhat2, &acts.rstd2, &p[r[LN2_W].clone()], &mut g[r[LN2_W].start..r[LN2_B].end], &mut dx);

        // Attention.
        let mut dout = dx.clone();
        if let Some(m) = drop {
            dout.iter_mut().zip(&m.attn).for_each(|(v, m)| *v *= m);
        }
        add_column_sums(&mut g[r[OUT_B].clone()], &dout);
        matmul(&mut g[r[OUT_W].clone()], View::rows(&dout, rows, dim).t(), View::rows(&acts.heads, rows, inner), true);
        let dheads = product(View::rows(&dout, rows, dim), View::rows(&p[r[OUT_W].clone()], dim, inner));
        let mut dqkv = vec![0f32; all * 3 * inner];
        attend_backward(d, tokens, queries, &acts.qkv, &acts.probs, &dheads, &mut dqkv);
        matmul(&mut g[r[QKV].clone()], View::rows(&dqkv, all, 3 * inner).t(), View::rows(&acts.a, all, dim), true);
        let da = product(View::rows(&dqkv, all, 3 * inner), View::rows(&w.qkv, 3 * inner, dim));
        // The residual's gradient reaches the computed rows; layer norm's, every row.
        let mut dx_all = if queries == tokens { dx } else { spread_first_rows(&dx, tokens * dim, queries * dim) };
        norm_rows_backward(&da, &acts.xhat1, &acts.rstd1, &p[r[LN1_W].clone()], &mut g[r[LN1_W].start..r[LN1_B].end], &mut dx_all);
        dx_all
    }

    /// Turns the gradients of the effective weights in `g` into those of the weights and masks.
    fn unfold_effective(&self, p: &[f32], g: &mut [f32]) {
        let (d, inner, r) = (self.dims.dim, self.dims.inner(), self.dims.ranges());
        let (w, mask) = (&p[r[QKV].clone()], &p[r[ATTN_MASK].clone()]);
        let mut dmask = vec![0f32; inner];
        for (row, (ge, wr)) in g[r[QKV].clone()].chunks_exact_mut(d).zip(w.chunks_exact(d)).enumerate() {
            let scale = if row < inner { self.dims.scale } else { 1.0 };
            let m = mask[row % inner];
            for (ge, w) in ge.iter_mut().zip(wr) {
                dmask[row % inner] += *ge * w * scale;
                *ge *= m * scale;
            }
        }
        g[r[ATTN_MASK].clone()].copy_from_slice(&dmask);
        let (w2, fmask, mlp) = (&p[r[FC2_W].clone()], &p[r[FFN_MASK].clone()], self.dims.mlp);
        let mut dfmask = vec![0f32; mlp];
        for (ge, wr) in g[r[FC2_W].clone()].chunks_exact_mut(mlp).zip(w2.chunks_exact(mlp)) {
            for j in 0..mlp {
                dfmask[j] += ge[j] * wr[j];
                ge[j] *= fmask[j];
            }
        }
        g[r[FFN_MASK].clone()].copy_from_slice(&dfmask);
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
        let (outputs, chunks): (Vec<Vec<f32>>, Vec<Activations>) =
            self.run_forward(x, p, &weights, sequences, tokens, self.keep).into_iter().unzip();
        if self.keep {
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

/// Layer normalisation of each `w.len()`-long row of `x`: `y = x̂ · w + b`, keeping `x̂` and `1/σ`.
#[inline(always)]
fn norm_rows(x: &[f32], w: &[f32], b: &[f32], eps: f32, xhat: &mut [f32], y: &mut [f32], rstd: &mut [f32]) {
    let d = w.len();
    for (((xr, hr), yr), r) in x.chunks_exact(d).zip(xhat.chunks_exact_mut(d)).zip(y.chunks_exact_mut(d)).zip(rstd.iter_mut()) {
        let mean = xr.iter().sum::<f32>() / d as f32;
        let var = xr.iter().map(|v| (v - mean) * (v - mean)).sum::<f32>() / d as f32;
        *r = 1.0 / (var + eps).sqrt();
        for i in 0..d {
            hr[i] = (xr[i] - mean) * *r;
            yr[i] = hr[i] * w[i] + b[i];
        }
    }
}

/// The backward of [`norm_rows`]: adds the input's gradient into `dx`, and the weight's and
/// bias's into `dwb` (weight, then bias).
#[inline(always)]
fn norm_rows_backward(dy: &[f32], xhat: &[f32], rstd: &[f32], w: &[f32], dwb: &mut [f32], dx: &mut [f32]) {
    let d = w.len();
    let (dw, db) = dwb.split_at_mut(d);
    let mut dxhat = vec![0f32; d];
    for (((gr, hr), &r), xr) in dy.chunks_exact(d).zip(xhat.chunks_exact(d)).zip(rstd).zip(dx.chunks_exact_mut(d)) {
        let (mut m1, mut m2) = (0f32, 0f32);
        for i in 0..d {
            dw[i] += gr[i] * hr[i];
            db[i] += gr[i];
            dxhat[i] = gr[i] * w[i];
            m1 += dxhat[i];
            m2 += dxhat[i] * hr[i];
        }
        let (m1, m2) = (m1 / d as f32, m2 / d as f32);
        for i in 0..d {
            xr[i] += r * (dxhat[i] - m1 - hr[i] * m2);
        }
    }
}

/// `y = x + (y + b) · mask`, row by row: a linear layer's bias, dropout and the residual.
#[inline(always)]
fn add_bias_dropout_residual(y: &mut [f32], b: &[f32], mask: Option<&[f32]>, x: &[f32]) {
    let d = b.len();
    let rows = y.chunks_exact_mut(d).zip(x.chunks_exact(d));
    match mask {
        Some(mask) => {
            for ((yr, xr), mr) in rows.zip(mask.chunks_exact(d)) {
                for j in 0..d {
                    yr[j] = xr[j] + (yr[j] + b[j]) * mr[j];
                }
            }
        }
        None => {
            for (yr, xr) in rows {
                for j in 0..d {
                    yr[j] = xr[j] + (yr[j] + b[j]);
                }
            }
        }
    }
}

/// `Φ(x)`, so that GELU (erf form) is `x · Φ(x)`.
#[inline(always)]
fn normal_cdf(x: f32) -> f32 {
    (libm::erff(x * std::f32::consts::FRAC_1_SQRT_2) + 1.0) * 0.5
}

/// GELU's derivative at `x`, `Φ(x) + x · φ(x)`, from `Φ(x)` kept by the forward pass.
#[inline(always)]
fn gelu_derivative(x: f32, cdf: f32) -> f32 {
    const INV_SQRT_2PI: f32 = 0.398_942_3;
    cdf + x * INV_SQRT_2PI * (-0.5 * x * x).exp()
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

/// Softmax attention of the first `queries` tokens of every sequence (all `tokens`, or the CLS
/// token) over all its tokens, for every head, from `qkv` (`[rows, 3 · inner]`, q then k then v,
/// the scale already in q): the probabilities `[sequences, heads, queries, tokens]` and the mixed
/// values `[sequences · queries, inner]`.
#[inline(always)]
fn attend(d: &BlockDims, tokens: usize, queries: usize, qkv: &[f32], probs: &mut [f32], heads: &mut [f32]) {
    let (inner, dh, l) = (d.inner(), d.dim_head, tokens);
    for (sh, p) in probs.chunks_exact_mut(queries * l).enumerate() {
        let (q, k, v, out) = head_offsets(d, tokens, queries, sh);
        if l >= GEMM_TOKENS {
            let view = |start: usize, rows: usize| View::strided(&qkv[start..], rows, dh, 3 * inner);
            matmul(p, view(q, queries), view(k, l).t(), false);
            p.chunks_exact_mut(l).for_each(softmax);
            matmul_strided(&mut heads[out..], inner, View::rows(p, queries, l), view(v, l), false);
            continue;
        }
        for (i, row) in p.chunks_exact_mut(l).enumerate() {
            let qi = &qkv[q + i * 3 * inner..][..dh];
            for (j, v) in row.iter_mut().enumerate() {
                *v = dot(qi, &qkv[k + j * 3 * inner..][..dh]);
            }
            softmax(row);
            let oi = &mut heads[out + i * inner..][..dh];
            oi.fill(0.0);
            for (j, &pj) in row.iter().enumerate() {
                axpy(oi, pj, &qkv[v + j * 3 * inner..][..dh]);
            }
        }
    }
}

#[inline(always)]
fn softmax(row: &mut [f32]) {
    let max = row.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    row.iter_mut().for_each(|v| *v = (*v - max).exp());
    let sum: f32 = row.iter().sum();
    row.iter_mut().for_each(|v| *v /= sum);
}

/// The backward of [`attend`]: from the mixed values' gradient `dheads`, writes q's, k's and v's
/// into `dqkv` (which starts at zero).
#[inline(always)]
fn attend_backward(d: &BlockDims, tokens: usize, queries: usize, qkv: &[f32], probs: &[f32], dheads: &[f32], dqkv: &mut [f32]) {
    let (inner, dh, l) = (d.inner(), d.dim_head, tokens);
    let mut ds = vec![0f32; if l >= GEMM_TOKENS { queries * l } else { l }];
    for (sh, p) in probs.chunks_exact(queries * l).enumerate() {
        let (q, k, v, dout) = head_offsets(d, tokens, queries, sh);
        if l >= GEMM_TOKENS {
            let view = |start: usize, rows: usize| View::strided(&qkv[start..], rows, dh, 3 * inner);
            let dov = View::strided(&dheads[dout..], queries, dh, inner);
            matmul(&mut ds, dov, view(v, l).t(), false);
            for (drow, prow) in ds.chunks_exact_mut(l).zip(p.chunks_exact(l)) {
                let mean = dot(prow, drow);
                drow.iter_mut().zip(prow).for_each(|(g, p)| *g = p * (*g - mean));
            }
            let (pv, dsv) = (View::rows(p, queries, l), View::rows(&ds, queries, l));
            matmul_strided(&mut dqkv[v..], 3 * inner, pv.t(), dov, false);
            matmul_strided(&mut dqkv[q..], 3 * inner, dsv, view(k, l), false);
            matmul_strided(&mut dqkv[k..], 3 * inner, dsv.t(), view(q, queries), false);
            continue;
        }
        for (i, prow) in p.chunks_exact(l).enumerate() {
            let doi = &dheads[dout + i * inner..][..dh];
            for (j, g) in ds.iter_mut().enumerate() {
                *g = dot(doi, &qkv[v + j * 3 * inner..][..dh]);
            }
            let mean = dot(prow, &ds);
            let qi = q + i * 3 * inner;
            for j in 0..l {
                let g = prow[j] * (ds[j] - mean);
                let (kj, vj) = (k + j * 3 * inner, v + j * 3 * inner);
                axpy(&mut dqkv[qi..][..dh], g, &qkv[kj..][..dh]);
                axpy(&mut dqkv[kj..][..dh], g, &qkv[qi..][..dh]);
                axpy(&mut dqkv[vj..][..dh], prow[j], doi);
            }
        }
    }
}

#[cfg(test)]
mod tests;
