//! PVT³'s token embedding as one candle op with a hand-written backward: patches → linear patch
//! embedding → × frame mask × patch mask → spatial CLS token in front → + position embedding. Composed of
//! candle ops, the backward of the masks and embeddings broadcast over the batch are strided
//! reductions on the training thread; fused, they are short loops.

use std::sync::OnceLock;

use candle_core::{CpuStorage, CustomOp2, Layout, Result, Shape, Storage, Tensor};

use crate::dense::{add_column_sums, add_to_rows, matmul, product, View};
use crate::fused_block::values;

/// The embedding's sizes: `tokens` temporal tokens of `patches` patches of `patch_dim` values,
/// embedded in `dim`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmbedDims {
    pub tokens: usize,
    pub patches: usize,
    pub patch_dim: usize,
    pub dim: usize,
}

impl EmbedDims {
    /// The packed parameters, in order: `patch_embed.weight` `[dim, patch_dim]`,
    /// `patch_embed.bias` `[dim]`, `frame_mask` `[tokens]`, `space_cls` `[dim]`, `pos_embed`
    /// `[tokens, patches + 1, dim]` and the patch scale `[patches]` (the patch mask's values,
    /// ones without one); their lengths.
    fn lengths(&self) -> [usize; 6] {
        let d = self.dim;
        [d * self.patch_dim, d, self.tokens, d, self.tokens * (self.patches + 1) * d, self.patches]
    }

    fn starts(&self) -> [usize; 6] {
        let mut start = 0;
        self.lengths().map(|len| {
            start += len;
            start - len
        })
    }
}

/// The embedding applied to patches `[batch, tokens, patches, patch_dim]`, giving
/// `[batch, tokens, patches + 1, dim]`.
pub struct EmbedOp {
    dims: EmbedDims,
    /// The patch embeddings before the masks, `[batch · tokens · patches, dim]`, for the
    /// mask's gradient.
    embedded: OnceLock<Vec<f32>>,
}

impl EmbedOp {
    pub fn new(dims: EmbedDims) -> Self {
        Self { dims, embedded: OnceLock::new() }
    }

    /// `packed`: the parameters of [`EmbedDims`] flattened and concatenated.
    pub fn apply(self, patches: &Tensor, packed: &Tensor) -> Result<Tensor> {
        patches.contiguous()?.apply_op2(&packed.contiguous()?, self)
    }

    fn embed(&self, x: &[f32], p: &[f32]) -> Vec<f32> {
        let (d, pd, s) = (self.dims.dim, self.dims.patch_dim, self.dims.starts());
        let mut e = product(View::rows(x, x.len() / pd, pd), View::rows(&p[s[0]..][..d * pd], d, pd).t());
        add_to_rows(&mut e, &p[s[1]..][..d]);
        e
    }
}

impl CustomOp2 for EmbedOp {
    fn name(&self) -> &'static str {
        "pvt3-fused-embedding"
    }

    fn cpu_fwd(&self, sx: &CpuStorage, lx: &Layout, sp: &CpuStorage, lp: &Layout) -> Result<(CpuStorage, Shape)> {
        let (b, t, n, pd) = lx.shape().dims4()?;
        let dm = self.dims;
        if (t, n, pd) != (dm.tokens, dm.patches, dm.patch_dim) || lp.shape().elem_count() != dm.lengths().iter().sum::<usize>() {
            candle_core::bail!("fused embedding: patches {:?} and {} parameters do not fit {dm:?}", lx.shape(), lp.shape().elem_count());
        }
        let (x, p) = (values(sx, lx)?, values(sp, lp)?);
        let (d, s) = (dm.dim, dm.starts());
        let (mask, cls, pos, scale) = (&p[s[2]..][..t], &p[s[3]..][..d], &p[s[4]..][..t * (n + 1) * d], &p[s[5]..][..n]);
        let e = self.embed(x, p);
        let mut out = Vec::with_capacity(b * t * (n + 1) * d);
        for (bt, rows) in e.chunks_exact(n * d).enumerate() {
            let k = bt % t;
            let pos = &pos[k * (n + 1) * d..][..(n + 1) * d];
            out.extend(cls.iter().zip(pos).map(|(c, q)| c + q));
            for ((row, pos), scale) in rows.chunks_exact(d).zip(pos[d..].chunks_exact(d)).zip(scale) {
                out.extend(row.iter().zip(pos).map(|(v, q)| v * mask[k] * scale + q));
            }
        }
        let _ = self.embedded.set(e);
        Ok((CpuStorage::F32(out), Shape::from((b, t, n + 1, d))))
    }

    fn bwd(&self, patches: &Tensor, packed: &Tensor, _res: &Tensor, grad: &Tensor) -> Result<(Option<Tensor>, Option<Tensor>)> {
        let (_, t, n, pd) = patches.dims4()?;
        let (d, s) = (self.dims.dim, self.dims.starts());
        let p = packed.flatten_all()?.to_vec1::<f32>()?;
        let g = grad.flatten_all()?.to_vec1::<f32>()?;
        // The patches as they are held, not copied: a camera's batch of them is most of a gigabyte.
        let patches = patches.contiguous()?;
        let (storage, layout) = patches.storage_and_layout();
        let x = match &*storage {
            Storage::Cpu(s) => values(s, layout)?,
            _ => candle_core::bail!("fused embedding: CPU tensors only"),
        };
        let recomputed;
        let e = match self.embedded.get() {
            Some(e) => e,
            None => {
                recomputed = self.embed(x, &p);
                &recomputed
            }
        };
        let (mask, scale) = (&p[s[2]..][..t], &p[s[5]..][..n]);
        let mut dp = vec![0f32; p.len()];
        // The gradient of the patch embeddings before the masks, `[rows, dim]`.
        let mut de = Vec::with_capacity(e.len());
        for (bt, (gs, es)) in g.chunks_exact((n + 1) * d).zip(e.chunks_exact(n * d)).enumerate() {
            let k = bt % t;
            add_column_sums(&mut dp[s[3]..][..d], &gs[..d]);
            dp[s[4] + k * (n + 1) * d..][..(n + 1) * d].iter_mut().zip(gs).for_each(|(a, v)| *a += v);
            let patch_grads = &gs[d..];
            // One sum over the token's patches, as without a patch mask (whose scale is one).
            let scaled = es.chunks_exact(d).zip(scale).flat_map(|(row, s)| row.iter().map(move |v| v * s));
            dp[s[2] + k] += patch_grads.iter().zip(scaled).map(|(a, b)| a * b).sum::<f32>();
            for (i, (gp, ep)) in patch_grads.chunks_exact(d).zip(es.chunks_exact(d)).enumerate() {
                dp[s[5] + i] += gp.iter().zip(ep).map(|(a, b)| a * b).sum::<f32>() * mask[k];
                de.extend(gp.iter().map(|v| v * mask[k] * scale[i]));
            }
        }
        let rows = de.len() / d;
        add_column_sums(&mut dp[s[1]..][..d], &de);
        matmul(&mut dp[s[0]..][..d * pd], View::rows(&de, rows, d).t(), View::rows(x, rows, pd), true);
        let dx = if patches.track_op() {
            Some(Tensor::from_vec(
                product(View::rows(&de, rows, d), View::rows(&p[s[0]..][..d * pd], d, pd)),
                patches.shape(),
                patches.device(),
            )?)
        } else {
            None
        };
        Ok((dx, Some(Tensor::from_vec(dp, packed.shape(), packed.device())?)))
    }
}

#[cfg(test)]
mod tests;
