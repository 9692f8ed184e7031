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
//!
//! [`BakedPvt3`] is plain data (no candle types), so the exporter can depend on it alone.

use std::collections::HashMap;

use serde::{Deserialize, Serialize};

use crate::reference;
use crate::{Config, Error, Result};

/// A dense layer: `weight` is `[rows, cols]` row-major (PyTorch's `[out, in]`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Dense {
    pub rows: usize,
    pub cols: usize,
    pub weight: Vec<f32>,
    pub bias: Option<Vec<f32>>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Norm {
    pub weight: Vec<f32>,
    pub bias: Vec<f32>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BakedAttention {
    pub heads: usize,
    /// Channels kept per head (may be 0: the block then adds only the output bias).
    pub head_dim: usize,
    /// The original `dim_head^-0.5`.
    pub scale: f32,
    /// `[heads · head_dim, dim]` each, head-major, masks folded in.
    pub q: Dense,
    pub k: Dense,
    pub v: Dense,
    /// `[dim, heads · head_dim]`.
    pub out: Dense,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BakedFeedForward {
    /// `[kept, dim]`.
    pub fc1: Dense,
    /// `[dim, kept]`, mask folded in.
    pub fc2: Dense,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BakedBlock {
    pub attn_norm: Norm,
    pub attn: BakedAttention,
    pub ffn_norm: Norm,
    pub ffn: BakedFeedForward,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BakedTransformer {
    pub layers: Vec<BakedBlock>,
    pub norm: Norm,
}

/// A baked PVT³: dense f32 weights, pruned channels and frames physically gone.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BakedPvt3 {
    /// The configuration of the masked parent (input layout, sizes before pruning).
    pub config: Config,
    pub patch_embed: Dense,
    /// Temporal tokens whose frames are read from the input, ascending.
    pub kept_tokens: Vec<usize>,
    /// The frame-mask value of each kept token, applied to its patch embeddings.
    pub token_scale: Vec<f32>,
    /// `[kept tokens, patches + 1, dim]`.
    pub pos_embed: Vec<f32>,
    pub space_cls: Vec<f32>,
    pub temporal_cls: Vec<f32>,
    /// `[time tokens, dim]`: the spatial encoding of each pruned token (zero rows for kept ones).
    pub pruned_encodings: Vec<f32>,
    pub space: BakedTransformer,
    pub temporal: BakedTransformer,
    pub head_norm: Norm,
    pub head: Dense,
}

/// Named tensors: shape and row-major values, as read from a checkpoint.
pub type Tensors = HashMap<String, (Vec<usize>, Vec<f32>)>;

struct Source<'a> {
    tensors: &'a Tensors,
}

impl Source<'_> {
    fn get(&self, name: &str, shape: &[usize]) -> Result<&[f32]> {
        let (s, v) = self.tensors.get(name).ok_or_else(|| Error::Config(format!("cannot bake: tensor `{name}` is missing")))?;
        if s.iter().product::<usize>() != shape.iter().product::<usize>() {
            return Err(Error::Config(format!("cannot bake: `{name}` has shape {s:?}, expected {shape:?}")));
        }
        Ok(v)
    }

    fn norm(&self, prefix: &str, dim: usize) -> Result<Norm> {
        Ok(Norm {
            weight: self.get(&format!("{prefix}.weight"), &[dim])?.to_vec(),
            bias: self.get(&format!("{prefix}.bias"), &[dim])?.to_vec(),
        })
    }

    fn dense(&self, prefix: &str, rows: usize, cols: usize, bias: bool) -> Result<Dense> {
        Ok(Dense {
            rows,
            cols,
            weight: self.get(&format!("{prefix}.weight"), &[rows, cols])?.to_vec(),
            bias: if bias { Some(self.get(&format!("{prefix}.bias"), &[rows])?.to_vec()) } else { None },
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
    let mask = src.get(&format!("{p}.channel_mask"), &[inner])?;
    let qkv = src.get(&format!("{p}.qkv.weight"), &[3 * inner, d])?;
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
    let out_w = src.get(&format!("{p}.out.weight"), &[d, inner])?;
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
            bias: Some(src.get(&format!("{p}.out.bias"), &[d])?.to_vec()),
        },
    })
}

fn bake_feed_forward(src: &Source, p: &str, cfg: &Config) -> Result<BakedFeedForward> {
    let (d, m) = (cfg.dim, cfg.mlp_dim);
    let mask = src.get(&format!("{p}.channel_mask"), &[m])?;
    let keep: Vec<usize> = (0..m).filter(|&u| mask[u] != 0.0).collect();
    let fc1 = src.dense(&format!("{p}.fc1"), m, d, true)?;
    let fc2 = src.dense(&format!("{p}.fc2"), d, m, true)?;
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
            let l = format!("{p}.layers.{i}");
            Ok(BakedBlock {
                attn_norm: src.norm(&format!("{l}.attn_norm"), cfg.dim)?,
                attn: bake_attention(src, &format!("{l}.attn"), cfg)?,
                ffn_norm: src.norm(&format!("{l}.ffn_norm"), cfg.dim)?,
                ffn: bake_feed_forward(src, &format!("{l}.ffn"), cfg)?,
            })
        })
        .collect::<Result<_>>()?;
    Ok(BakedTransformer { layers, norm: src.norm(&format!("{p}.norm"), cfg.dim)? })
}

/// Bakes the masked model `cfg` with weights `tensors` (the checkpoint names).
pub fn bake(cfg: &Config, tensors: &Tensors) -> Result<BakedPvt3> {
    cfg.validate()?;
    cfg.require_pvt3("baking (and so ONNX export)")?;
    let src = Source { tensors };
    let (t, n, d) = (cfg.time_tokens(), cfg.num_patches(), cfg.dim);
    let frame_mask = src.get("frame_mask", &[t])?;
    let kept_tokens: Vec<usize> = (0..t).filter(|&k| frame_mask[k] != 0.0).collect();
    let pos = src.get("pos_embed", &[1, t, n + 1, d])?;
    let row = (n + 1) * d;
    let space_cls = src.get("space_cls", &[1, 1, d])?.to_vec();
    let space = bake_transformer(&src, "space", cfg.space_depth, cfg)?;
    // A pruned token's spatial input is the CLS token and the position embedding alone.
    let mut pruned_encodings = vec![0f32; t * d];
    for k in (0..t).filter(|k| frame_mask[*k] == 0.0) {
        let mut tokens: Vec<f64> = pos[k * row..(k + 1) * row].iter().map(|v| *v as f64).collect();
        tokens.iter_mut().zip(&space_cls).for_each(|(v, c)| *v += *c as f64);
        let encoded = reference::transformer_cls(&space, &tokens, n + 1, d, cfg.layer_norm_eps);
        pruned_encodings[k * d..(k + 1) * d].iter_mut().zip(encoded).for_each(|(o, v)| *o = v as f32);
    }
    Ok(BakedPvt3 {
        config: cfg.clone(),
        patch_embed: src.dense("patch_embed", d, cfg.patch_dim(), true)?,
        token_scale: kept_tokens.iter().map(|&k| frame_mask[k]).collect(),
        pos_embed: kept_tokens.iter().flat_map(|&k| pos[k * row..(k + 1) * row].iter().copied()).collect(),
        kept_tokens,
        space_cls,
        temporal_cls: src.get("temporal_cls", &[1, 1, d])?.to_vec(),
        pruned_encodings,
        space,
        temporal: bake_transformer(&src, "temporal", cfg.time_depth, cfg)?,
        head_norm: src.norm("head_norm", d)?,
        head: src.dense("head", cfg.classes, d, true)?,
    })
}

impl BakedPvt3 {
    /// Trainable values left after baking (the frame scale included).
    pub fn parameter_count(&self) -> usize {
        let dense = |l: &Dense| l.weight.len() + l.bias.as_ref().map_or(0, Vec::len);
        let norm = |n: &Norm| n.weight.len() + n.bias.len();
        let transformer = |t: &BakedTransformer| {
            norm(&t.norm)
                + t.layers
                    .iter()
                    .map(|b| {
                        let a = &b.attn;
                        norm(&b.attn_norm)
                            + norm(&b.ffn_norm)
                            + dense(&a.q)
                            + dense(&a.k)
                            + dense(&a.v)
                            + dense(&a.out)
                            + dense(&b.ffn.fc1)
                            + dense(&b.ffn.fc2)
                    })
                    .sum::<usize>()
        };
        dense(&self.patch_embed)
            + self.token_scale.len()
            + self.pos_embed.len()
            + self.space_cls.len()
            + self.temporal_cls.len()
            + transformer(&self.space)
            + transformer(&self.temporal)
            + norm(&self.head_norm)
            + dense(&self.head)
    }

    /// "N parameters, M multiply-adds per sample, k of T temporal tokens kept".
    pub fn size_summary(&self) -> String {
        format!(
            "{} parameters, {} multiply-adds per sample, {} of {} temporal tokens kept",
            self.parameter_count(),
            self.mult_adds(),
            self.kept_tokens.len(),
            self.config.time_tokens()
        )
    }

    /// Multiply-adds per sample (matrix products only), as [`Config::mult_adds`] counts them.
    pub fn mult_adds(&self) -> u64 {
        let c = &self.config;
        let (n, t) = (c.num_patches(), c.time_tokens());
        let layer = |b: &BakedBlock, seqs: usize, len: usize| {
            let a = &b.attn;
            let inner = a.heads * a.head_dim;
            let per_token = (a.q.weight.len()
                + a.k.weight.len()
                + a.v.weight.len()
                + a.out.weight.len()
                + b.ffn.fc1.weight.len()
                + b.ffn.fc2.weight.len()) as u64;
            seqs as u64 * (len as u64 * per_token + 2 * (len * len * inner) as u64)
        };
        let kept = self.kept_tokens.len();
        let embed = (kept * n * self.patch_embed.weight.len()) as u64;
        let space: u64 = self.space.layers.iter().map(|b| layer(b, kept, n + 1)).sum();
        let time: u64 = self.temporal.layers.iter().map(|b| layer(b, 1, t + 1)).sum();
        embed + space + time + self.head.weight.len() as u64
    }
}

#[cfg(test)]
mod tests;
