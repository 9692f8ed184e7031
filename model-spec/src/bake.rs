//! Baking: a masked PVT³ becomes a smaller dense model computing the same function.
//!
//! - Attention: a q/k/v channel whose mask is zero is removed (rows of W_q, W_k, W_v, columns of
//!   W_out); surviving mask values are folded into the q/k/v rows. With several heads every head
//!   keeps the same number of channels (a head with fewer non-zero channels keeps some zero-mask
//!   ones, which contribute nothing), so heads stay uniform. The scale stays `dim_head^-0.5` of
//!   the original model.
//! - Feed-forward: a zero-mask unit removes a row of fc1 and a column of fc2; surviving mask
//!   values scale fc2's columns.
//! - Frames: a temporal token whose frame-mask value is zero no longer sees its input: its patch
//!   embeddings are zero, so its spatial encoding is a constant of the weights. Baking computes
//!   that constant once; the baked model gathers only the kept frames from the input, encodes
//!   them, and puts the constants in the pruned places of the temporal sequence.
//! - Patches: a patch whose patch-mask value is zero has no token in the masked model
//!   (`Pvt3Config::patch_selection`), so the baked one neither reads nor embeds it: its
//!   position-embedding rows go, and the surviving mask values scale the kept patches'
//!   embeddings.
//!
//! The result, [`BakedPvt3`] (`crate::baked`), is plain data (no candle types), so the exporter
//! can depend on it alone.

use crate::baked::{BakedAttention, BakedBlock, BakedFeedForward, BakedPvt3, BakedSpectrum, BakedTransformer, Dense, Norm};
use crate::names::{
    join, layer, spectral, ATTN, ATTN_NORM, BIAS, CHANNEL_MASK, FC1, FC2, FFN, FFN_NORM, FRAME_MASK, HEAD, HEAD_NORM, LINEAR, NORM, OUT,
    PATCH_EMBED, PATCH_MASK, POS_EMBED, QKV, SCALE, SHIFT, SPACE, SPACE_CLS, TEMPORAL, TEMPORAL_CLS, WEIGHT,
};
use crate::reference;
use crate::weights::Tensors;
use crate::{Config, Error, Result};

struct Source<'a> {
    tensors: &'a Tensors,
}

impl Source<'_> {
    fn get(&self, name: &str, shape: &[usize]) -> Result<&[f32]> {
        let (s, v) = self.tensors.get(name).ok_or_else(|| Error::MissingTensor { task: "bake", name: name.into() })?;
        if s.iter().product::<usize>() != shape.iter().product::<usize>() {
            return Err(Error::TensorShape { task: "bake", name: name.into(), got: s.clone(), expected: shape.to_vec() });
        }
        Ok(v)
    }

    fn norm(&self, prefix: &str, dim: usize) -> Result<Norm> {
        Ok(Norm { weight: self.get(&join(&[prefix, WEIGHT]), &[dim])?.to_vec(), bias: self.get(&join(&[prefix, BIAS]), &[dim])?.to_vec() })
    }

    fn dense(&self, prefix: &str, rows: usize, cols: usize, bias: bool) -> Result<Dense> {
        Ok(Dense {
            rows,
            cols,
            weight: self.get(&join(&[prefix, WEIGHT]), &[rows, cols])?.to_vec(),
            bias: if bias { Some(self.get(&join(&[prefix, BIAS]), &[rows])?.to_vec()) } else { None },
        })
    }
}

/// Rows `keep` of a `[rows, cols]` matrix, row i scaled by `scale[i]`.
fn take_rows(w: &[f32], cols: usize, keep: &[usize], scale: impl Fn(usize) -> f32) -> Vec<f32> {
    let scale = &scale;
    keep.iter().flat_map(|&r| w[r * cols..(r + 1) * cols].iter().map(move |v| v * scale(r))).collect()
}

/// Columns `keep` of a `[rows, cols]` matrix, column j scaled by `scale[j]`.
fn take_cols(w: &[f32], rows: usize, cols: usize, keep: &[usize], scale: impl Fn(usize) -> f32) -> Vec<f32> {
    (0..rows).flat_map(|r| keep.iter().map(move |&c| (r, c))).map(|(r, c)| w[r * cols + c] * scale(c)).collect()
}

fn bake_attention(src: &Source, p: &str, cfg: &Config) -> Result<BakedAttention> {
    let (d, h, dh) = (cfg.dim, cfg.heads, cfg.dim_head);
    let inner = h * dh;
    let mask = src.get(&join(&[p, CHANNEL_MASK]), &[inner])?;
    let qkv = src.get(&join(&[p, QKV, WEIGHT]), &[3 * inner, d])?;
    // The same number of channels per head: the non-zero ones, topped up with zero ones.
    let per_head: Vec<Vec<usize>> = (0..h).map(|head| (head * dh..(head + 1) * dh).filter(|&c| mask[c] != 0.0).collect()).collect();
    let head_dim = per_head.iter().map(Vec::len).max().unwrap_or(0);
    let keep: Vec<usize> = (0..h)
        .flat_map(|head| {
            let mut chosen = per_head[head].clone();
            chosen.extend((head * dh..(head + 1) * dh).filter(|c| mask[*c] == 0.0).take(head_dim - chosen.len()));
            chosen.sort_unstable();
            chosen
        })
        .collect();
    let block = |i: usize| Dense {
        rows: keep.len(),
        cols: d,
        weight: take_rows(&qkv[i * inner * d..(i + 1) * inner * d], d, &keep, |c| mask[c]),
        bias: None,
    };
    let out_w = src.get(&join(&[p, OUT, WEIGHT]), &[d, inner])?;
    Ok(BakedAttention {
        heads: h,
        head_dim,
        scale: (dh as f32).powf(-0.5),
        q: block(0),
        k: block(1),
        v: block(2),
        out: Dense {
            rows: d,
            cols: keep.len(),
            weight: take_cols(out_w, d, inner, &keep, |_| 1.0),
            bias: Some(src.get(&join(&[p, OUT, BIAS]), &[d])?.to_vec()),
        },
    })
}

fn bake_feed_forward(src: &Source, p: &str, cfg: &Config) -> Result<BakedFeedForward> {
    let (d, m) = (cfg.dim, cfg.mlp_dim);
    let mask = src.get(&join(&[p, CHANNEL_MASK]), &[m])?;
    let keep: Vec<usize> = (0..m).filter(|&u| mask[u] != 0.0).collect();
    let fc1 = src.dense(&join(&[p, FC1]), m, d, true)?;
    let fc2 = src.dense(&join(&[p, FC2]), d, m, true)?;
    let fc1_bias = fc1.bias.as_deref().expect("fc1 has a bias");
    Ok(BakedFeedForward {
        fc1: Dense {
            rows: keep.len(),
            cols: d,
            weight: take_rows(&fc1.weight, d, &keep, |_| 1.0),
            bias: Some(keep.iter().map(|&u| fc1_bias[u]).collect()),
        },
        fc2: Dense { rows: d, cols: keep.len(), weight: take_cols(&fc2.weight, d, m, &keep, |u| mask[u]), bias: fc2.bias },
    })
}

fn bake_transformer(src: &Source, p: &str, depth: usize, cfg: &Config) -> Result<BakedTransformer> {
    let layers = (0..depth)
        .map(|i| {
            let l = layer(p, i);
            Ok(BakedBlock {
                attn_norm: src.norm(&join(&[&l, ATTN_NORM]), cfg.dim)?,
                attn: bake_attention(src, &join(&[&l, ATTN]), cfg)?,
                ffn_norm: src.norm(&join(&[&l, FFN_NORM]), cfg.dim)?,
                ffn: bake_feed_forward(src, &join(&[&l, FFN]), cfg)?,
            })
        })
        .collect::<Result<_>>()?;
    Ok(BakedTransformer { layers, norm: src.norm(&join(&[p, NORM]), cfg.dim)? })
}

/// Bakes the masked model `cfg` with weights `tensors` (the checkpoint names).
pub fn bake(cfg: &Config, tensors: &Tensors) -> Result<BakedPvt3> {
    cfg.validate()?;
    cfg.require_pvt3("baking (and so ONNX export)")?;
    let src = Source { tensors };
    let (t, n, d) = (cfg.time_tokens(), cfg.num_patches(), cfg.dim);
    let frame_mask = src.get(FRAME_MASK, &[t])?;
    let kept_tokens: Vec<usize> = (0..t).filter(|&k| frame_mask[k] != 0.0).collect();
    let patch_mask = if cfg.patch_selection() { src.get(PATCH_MASK, &[n])?.to_vec() } else { vec![1.0; n] };
    let kept_patches: Vec<usize> = (0..n).filter(|&p| patch_mask[p] != 0.0).collect();
    // Each token's position embedding: the CLS token's row, then the kept patches'.
    let pos = src.get(POS_EMBED, &[1, t, n + 1, d])?;
    let rows: Vec<usize> = std::iter::once(0).chain(kept_patches.iter().map(|p| p + 1)).collect();
    let positions = |k: usize| rows.iter().flat_map(move |r| pos[(k * (n + 1) + r) * d..][..d].iter().copied());
    let space_cls = src.get(SPACE_CLS, &[1, 1, d])?.to_vec();
    let space = bake_transformer(&src, SPACE, cfg.space_depth, cfg)?;
    // A pruned token's spatial input is the CLS token and the position embedding alone.
    let mut pruned_encodings = vec![0f32; t * d];
    for k in (0..t).filter(|k| frame_mask[*k] == 0.0) {
        let mut tokens: Vec<f64> = positions(k).map(|v| v as f64).collect();
        tokens.iter_mut().zip(&space_cls).for_each(|(v, c)| *v += *c as f64);
        let encoded = reference::transformer_cls(&space, &tokens, rows.len(), d, cfg.layer_norm_eps);
        pruned_encodings[k * d..(k + 1) * d].iter_mut().zip(encoded).for_each(|(o, v)| *o = v as f32);
    }
    Ok(BakedPvt3 {
        config: cfg.clone(),
        patch_embed: src.dense(PATCH_EMBED, d, cfg.patch_dim(), true)?,
        token_scale: kept_tokens.iter().map(|&k| frame_mask[k]).collect(),
        pos_embed: kept_tokens.iter().flat_map(|&k| positions(k)).collect(),
        kept_tokens,
        patch_scale: kept_patches.iter().map(|&p| patch_mask[p]).collect(),
        kept_patches,
        space_cls,
        temporal_cls: src.get(TEMPORAL_CLS, &[1, 1, d])?.to_vec(),
        pruned_encodings,
        space,
        temporal: bake_transformer(&src, TEMPORAL, cfg.time_depth, cfg)?,
        head_norm: src.norm(HEAD_NORM, d)?,
        head: src.dense(HEAD, cfg.classes, d, true)?,
        spectrum: bake_spectrum(&src, cfg)?,
    })
}

fn bake_spectrum(src: &Source, cfg: &Config) -> Result<Option<BakedSpectrum>> {
    let f = cfg.spectral_features();
    if f == 0 {
        return Ok(None);
    }
    Ok(Some(BakedSpectrum {
        scale: src.get(&spectral(SCALE), &[f])?.to_vec(),
        shift: src.get(&spectral(SHIFT), &[f])?.to_vec(),
        linear: src.dense(&spectral(LINEAR), cfg.classes, f, true)?,
    }))
}
