//! The model's variables, named once. Every name a checkpoint holds is built from the parts
//! below: the candle modules pass them to `vb.pp(..)`, and baking, pruning, the fused block's
//! pack, initialisation, the optimiser's weight decay and the spectral fit read them from here.
//! [`pvt3_variables`] is the whole table for a PVT³ (name, shape, [`Role`]); a test in
//! `pvt3-models` checks that a fresh model has exactly these variables.
//!
//! The parts follow the golden checkpoint (`tests/golden/icub20/manifest.json`), which follows
//! the PyTorch implementation: Linear weights `[out, in]`, norms `weight` and `bias`.

use crate::Config;

/// A linear layer's or a norm's scale (candle-nn's and PyTorch's name).
pub const WEIGHT: &str = "weight";
/// A linear layer's or a norm's shift.
pub const BIAS: &str = "bias";

pub const PATCH_EMBED: &str = "patch_embed";
/// PVT³'s frame-selection mask, one entry per temporal token.
pub const FRAME_MASK: &str = "frame_mask";
/// PVT³'s patch-selection mask, one entry per patch of the grid (`Pvt3Config::patch_selection`).
pub const PATCH_MASK: &str = "patch_mask";
pub const POS_EMBED: &str = "pos_embed";
pub const SPACE_CLS: &str = "space_cls";
pub const TEMPORAL_CLS: &str = "temporal_cls";
/// The ViT baseline's CLS token.
pub const CLS: &str = "cls";
/// The spatial transformer (PVT³).
pub const SPACE: &str = "space";
/// The temporal transformer (PVT³).
pub const TEMPORAL: &str = "temporal";
/// The ViT baseline's one transformer.
pub const TRANSFORMER: &str = "transformer";
/// A transformer's blocks: `{transformer}.layers.{i}`.
pub const LAYERS: &str = "layers";
/// A transformer's final norm.
pub const NORM: &str = "norm";
pub const HEAD_NORM: &str = "head_norm";
pub const HEAD: &str = "head";

/// Inside a block.
pub const ATTN_NORM: &str = "attn_norm";
pub const ATTN: &str = "attn";
pub const FFN_NORM: &str = "ffn_norm";
pub const FFN: &str = "ffn";
/// Attention: q, k and v stacked, `[3 · inner, dim]`, no bias.
pub const QKV: &str = "qkv";
pub const OUT: &str = "out";
/// The channel-selection mask of an attention (its q/k/v channels) or a feed-forward (its units).
pub const CHANNEL_MASK: &str = "channel_mask";
pub const FC1: &str = "fc1";
pub const FC2: &str = "fc2";

/// An LSTM's variables (PyTorch's names, one layer): input and hidden weights and biases.
pub const WEIGHT_IH: &str = "weight_ih_l0";
pub const WEIGHT_HH: &str = "weight_hh_l0";
pub const BIAS_IH: &str = "bias_ih_l0";
pub const BIAS_HH: &str = "bias_hh_l0";
pub const LSTM: [&str; 4] = [WEIGHT_IH, WEIGHT_HH, BIAS_IH, BIAS_HH];

/// PVT³'s spectral head: `spectral.{scale, shift, linear.*}`.
pub const SPECTRAL: &str = "spectral";
pub const SCALE: &str = "scale";
pub const SHIFT: &str = "shift";
pub const LINEAR: &str = "linear";

/// What a variable is: how it starts, and what weight decay, pruning and the spectral fit do with
/// it. Read from its name by [`Role::of`], for every architecture.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// A selection mask (channels, frames or patches): starts at one, trained at its own rate, pruned by
    /// magnitude.
    Mask,
    /// A layer norm's scale: starts at one.
    NormScale,
    /// A layer norm's shift: starts at zero.
    NormShift,
    /// A weight matrix `[out, in]`: weight decay and random pruning apply.
    Matrix,
    /// Any other weight of a layer (a bias, a convolution kernel): PyTorch's start, uniform within
    /// ±1/√fan-in of its layer.
    Layer,
    /// A position embedding or a CLS token: starts small (std 0.02).
    Embedding,
    /// The spectral head's standardisation scale: starts at one, fitted to the training set.
    StandardScale,
    /// The spectral head's standardisation shift: starts at zero, fitted to the training set.
    StandardShift,
}

impl Role {
    /// Fitted to the training set before the first step and held there, not trained: the
    /// spectral head's standardisation. Trained, its scale grows free of weight decay and lets the
    /// head fit the training touches' spectra (docs/robustness.md, "A standardisation fitted").
    pub fn is_fitted(self) -> bool {
        matches!(self, Role::StandardScale | Role::StandardShift)
    }

    /// The role of variable `name` of `rank` axes.
    pub fn of(name: &str, rank: usize) -> Role {
        let (parent, leaf) = name.rsplit_once('.').unwrap_or(("", name));
        let is_norm = parent.ends_with(NORM);
        match leaf {
            _ if leaf == FRAME_MASK || leaf == PATCH_MASK || leaf == CHANNEL_MASK => Role::Mask,
            WEIGHT if is_norm => Role::NormScale,
            BIAS if is_norm => Role::NormShift,
            SCALE if parent == SPECTRAL => Role::StandardScale,
            SHIFT if parent == SPECTRAL => Role::StandardShift,
            _ if leaf == POS_EMBED || leaf == SPACE_CLS || leaf == TEMPORAL_CLS || leaf == CLS => Role::Embedding,
            WEIGHT if rank == 2 => Role::Matrix,
            _ => Role::Layer,
        }
    }
}

/// `parts` joined into one variable name (`space.layers.0.attn.qkv.weight`).
pub fn join(parts: &[&str]) -> String {
    parts.join(".")
}

/// Block `i` of transformer `stage` (`space.layers.3`).
pub fn layer(stage: &str, i: usize) -> String {
    format!("{stage}.{LAYERS}.{i}")
}

/// The spectral head's variables.
pub fn spectral(leaf: &str) -> String {
    join(&[SPECTRAL, leaf])
}

/// One variable of the table: its name, shape and role.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Variable {
    pub name: String,
    pub shape: Vec<usize>,
    pub role: Role,
}

impl Variable {
    fn new(name: String, shape: Vec<usize>) -> Self {
        let role = Role::of(&name, shape.len());
        Self { name, shape, role }
    }
}

/// The sizes a block's shapes are written in.
#[derive(Clone, Copy, Debug)]
pub enum Size {
    /// The embedding width.
    Dim,
    /// q, k or v: heads × dim_head.
    Inner,
    /// q, k and v stacked.
    Inner3,
    /// The feed-forward's hidden width.
    Mlp,
}

impl Size {
    /// The size in a block of width `dim`, attention width `inner` and feed-forward width `mlp`.
    pub fn of(self, dim: usize, inner: usize, mlp: usize) -> usize {
        match self {
            Size::Dim => dim,
            Size::Inner => inner,
            Size::Inner3 => 3 * inner,
            Size::Mlp => mlp,
        }
    }
}

/// One transformer block's variables relative to its [`layer`] prefix, with their shapes, in the
/// order the fused training op packs them.
pub const BLOCK: [(&[&str], &[Size]); 13] = [
    (&[ATTN_NORM, WEIGHT], &[Size::Dim]),
    (&[ATTN_NORM, BIAS], &[Size::Dim]),
    (&[ATTN, QKV, WEIGHT], &[Size::Inner3, Size::Dim]),
    (&[ATTN, CHANNEL_MASK], &[Size::Inner]),
    (&[ATTN, OUT, WEIGHT], &[Size::Dim, Size::Inner]),
    (&[ATTN, OUT, BIAS], &[Size::Dim]),
    (&[FFN_NORM, WEIGHT], &[Size::Dim]),
    (&[FFN_NORM, BIAS], &[Size::Dim]),
    (&[FFN, FC1, WEIGHT], &[Size::Mlp, Size::Dim]),
    (&[FFN, FC1, BIAS], &[Size::Mlp]),
    (&[FFN, FC2, WEIGHT], &[Size::Dim, Size::Mlp]),
    (&[FFN, FC2, BIAS], &[Size::Dim]),
    (&[FFN, CHANNEL_MASK], &[Size::Mlp]),
];

/// The two transformers of PVT³ with their depths.
pub fn stages(cfg: &Config) -> [(&'static str, usize); 2] {
    [(SPACE, cfg.space_depth), (TEMPORAL, cfg.time_depth)]
}

/// Every variable of the PVT³ `cfg` describes, in a fixed order: what its checkpoint holds.
pub fn pvt3_variables(cfg: &Config) -> Vec<Variable> {
    let (d, t, n) = (cfg.dim, cfg.time_tokens(), cfg.num_patches());
    let linear = |prefix: &str, out: usize, inp: usize| {
        [Variable::new(join(&[prefix, WEIGHT]), vec![out, inp]), Variable::new(join(&[prefix, BIAS]), vec![out])]
    };
    let norm = |prefix: &str| [Variable::new(join(&[prefix, WEIGHT]), vec![d]), Variable::new(join(&[prefix, BIAS]), vec![d])];
    let mut vars = Vec::new();
    vars.extend(linear(PATCH_EMBED, d, cfg.patch_dim()));
    vars.push(Variable::new(FRAME_MASK.into(), vec![t]));
    if cfg.patch_selection() {
        vars.push(Variable::new(PATCH_MASK.into(), vec![n]));
    }
    vars.push(Variable::new(POS_EMBED.into(), vec![1, t, n + 1, d]));
    vars.push(Variable::new(SPACE_CLS.into(), vec![1, 1, d]));
    vars.push(Variable::new(TEMPORAL_CLS.into(), vec![1, 1, d]));
    for (stage, depth) in stages(cfg) {
        for i in 0..depth {
            let prefix = layer(stage, i);
            for (path, shape) in BLOCK {
                let name = std::iter::once(prefix.as_str()).chain(path.iter().copied()).collect::<Vec<_>>();
                let shape = shape.iter().map(|s| s.of(d, cfg.inner_dim(), cfg.mlp_dim)).collect();
                vars.push(Variable::new(join(&name), shape));
            }
        }
        vars.extend(norm(&join(&[stage, NORM])));
    }
    vars.extend(norm(HEAD_NORM));
    vars.extend(linear(HEAD, cfg.classes, d));
    if cfg.spectral_bands() > 0 {
        let f = cfg.spectral_features();
        vars.push(Variable::new(spectral(SCALE), vec![f]));
        vars.push(Variable::new(spectral(SHIFT), vec![f]));
        vars.extend(linear(&spectral(LINEAR), cfg.classes, f));
    }
    vars
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_counts_the_published_parameters_and_names_the_golden_tensors() {
        let cfg = Config::icub20();
        let vars = pvt3_variables(&cfg);
        let count =
            |keep: &dyn Fn(&Variable) -> bool| vars.iter().filter(|v| keep(v)).map(|v| v.shape.iter().product::<usize>()).sum::<usize>();
        // 64,272 trainable parameters besides the masks (DESIGN.md); the masks are 75 frames
        // and 8 blocks × (64 + 40) channels.
        assert_eq!(count(&|v| v.role != Role::Mask), 64_272 - 2 * 4 * (64 + 40));
        assert_eq!(count(&|v| v.role == Role::Mask), 75 + 8 * (64 + 40));
        let manifest = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/golden/icub20/manifest.json")).unwrap();
        for v in &vars {
            assert!(manifest.contains(&format!("\"{}\"", v.name)), "{} is not a golden tensor", v.name);
        }
        let mut names: Vec<&str> = vars.iter().map(|v| v.name.as_str()).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), vars.len(), "a name twice");
    }

    #[test]
    fn roles_follow_the_names() {
        let role = |name: &str, rank| Role::of(name, rank);
        assert_eq!(role("space.layers.0.attn.channel_mask", 1), Role::Mask);
        assert_eq!(role("frame_mask", 1), Role::Mask);
        assert_eq!(role("temporal.norm.weight", 1), Role::NormScale);
        assert_eq!(role("head_norm.bias", 1), Role::NormShift);
        assert_eq!(role("space.layers.1.attn_norm.weight", 1), Role::NormScale);
        assert_eq!(role("space.layers.1.attn.qkv.weight", 2), Role::Matrix);
        assert_eq!(role("head.bias", 1), Role::Layer);
        assert_eq!(role("conv.weight", 4), Role::Layer);
        assert_eq!(role("encoder.weight_ih_l0", 2), Role::Layer);
        assert_eq!(role("pos_embed", 4), Role::Embedding);
        assert_eq!(role("cls", 3), Role::Embedding);
        assert_eq!(role("spectral.scale", 1), Role::StandardScale);
        assert_eq!(role("spectral.shift", 1), Role::StandardShift);
        assert_eq!(role("spectral.linear.weight", 2), Role::Matrix);
    }
}
