//! A baked PVT³: plain dense f32 weights, pruned channels and frames physically gone (what
//! [`crate::bake::bake`] makes of a masked model). No candle types, so the exporter and the f64
//! reference depend on it alone.

use serde::{Deserialize, Serialize};

use crate::Config;

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

/// The spectral head (`crate::spectrum`), as trained: pruning leaves it whole.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BakedSpectrum {
    /// `[features]` each: the standardisation, `feature · scale + shift`.
    pub scale: Vec<f32>,
    pub shift: Vec<f32>,
    /// `[classes, features]`.
    pub linear: Dense,
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
    /// Patches of the grid (row-major) that are read from the input and embedded, ascending:
    /// all of them unless the patch mask pruned some.
    pub kept_patches: Vec<usize>,
    /// The patch-mask value of each kept patch (ones without a patch mask), applied to its
    /// embeddings.
    pub patch_scale: Vec<f32>,
    /// `[kept tokens, kept patches + 1, dim]`.
    pub pos_embed: Vec<f32>,
    pub space_cls: Vec<f32>,
    pub temporal_cls: Vec<f32>,
    /// `[time tokens, dim]`: the spatial encoding of each pruned token (zero rows for kept ones).
    pub pruned_encodings: Vec<f32>,
    pub space: BakedTransformer,
    pub temporal: BakedTransformer,
    pub head_norm: Norm,
    pub head: Dense,
    /// The spectral head, when the configuration has one; written only then.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spectrum: Option<BakedSpectrum>,
}

impl BakedPvt3 {
    /// Trainable values left after baking (the frame and patch scales included).
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
            + if self.config.patch_selection() { self.patch_scale.len() } else { 0 }
            + self.pos_embed.len()
            + self.space_cls.len()
            + self.temporal_cls.len()
            + transformer(&self.space)
            + transformer(&self.temporal)
            + norm(&self.head_norm)
            + dense(&self.head)
            + self.spectrum.as_ref().map_or(0, |s| s.scale.len() + s.shift.len() + dense(&s.linear))
    }

    /// "N parameters, M multiply-adds per sample, k of T temporal tokens kept" (and ", j of P
    /// patches kept" for a model with a patch mask).
    pub fn size_summary(&self) -> String {
        let patches = if self.config.patch_selection() {
            format!(", {} of {} patches kept", self.kept_patches.len(), self.config.num_patches())
        } else {
            String::new()
        };
        format!(
            "{} parameters, {} multiply-adds per sample, {} of {} temporal tokens kept{patches}",
            self.parameter_count(),
            self.mult_adds(),
            self.kept_tokens.len(),
            self.config.time_tokens()
        )
    }

    /// Multiply-adds per sample (matrix products only), as [`Config::mult_adds`] counts them.
    pub fn mult_adds(&self) -> u64 {
        let c = &self.config;
        let (n, t) = (self.kept_patches.len(), c.time_tokens());
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
        embed + space + time + self.head.weight.len() as u64 + c.spectral_mult_adds()
    }
}
