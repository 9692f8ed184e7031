//! The fused block's forward pass: every chunk of sequences in parallel, and the row kernels it
//! runs (layer norm, attention, bias, dropout and residual, GELU).

use std::ops::Range;

use rayon::prelude::*;

use super::dropout::first_rows;
use super::layout::*;
use super::{head_offsets, Activations, BlockOp, Effective, GEMM_TOKENS};
use crate::dense::{add_to_rows, axpy, dot, matmul, matmul_strided, product, View};

impl BlockOp {
    /// The forward pass of every chunk, in parallel: outputs and (if kept) activations.
    pub(super) fn run_forward(
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
