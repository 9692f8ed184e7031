//! The fused block's backward pass: one chunk's gradients from its kept (or recomputed)
//! activations, and the masks' and scale's gradients unfolded from the effective weights.

use super::dropout::spread_first_rows;
use super::layout::*;
use super::{head_offsets, Activations, BlockOp, Effective, GEMM_TOKENS};
use crate::dense::{add_column_sums, axpy, dot, matmul, matmul_strided, product, View};

impl BlockOp {
    with_avx2! {
        /// The backward pass of one chunk: the input's gradient, and into `g` (laid out as the
        /// packed parameters) the gradients of the effective q/k/v and second-layer weights, the
        /// others as they are.
        pub(super) fn backward_chunk / backward_chunk_avx2 => backward_chunk_body(p: &[f32], w: &Effective, acts: &Activations, dy: &[f32], tokens: usize, g: &mut [f32]) -> Vec<f32>
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
    pub(super) fn unfold_effective(&self, p: &[f32], g: &mut [f32]) {
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
}

/// The backward of `forward::norm_rows`: adds the input's gradient into `dx`, and the weight's and
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

/// GELU's derivative at `x`, `Φ(x) + x · φ(x)`, from `Φ(x)` kept by the forward pass.
#[inline(always)]
fn gelu_derivative(x: f32, cdf: f32) -> f32 {
    const INV_SQRT_2PI: f32 = 0.398_942_3;
    cdf + x * INV_SQRT_2PI * (-0.5 * x * x).exp()
}

/// The backward of `forward::attend`: from the mixed values' gradient `dheads`, writes q's, k's and v's
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
