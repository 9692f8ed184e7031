//! The PVT³ model: patch embedding, frame-selection mask, spatial transformer per temporal token,
//! temporal transformer over the spatial CLS outputs, and a classification head.
//!
//! Patch flattening follows the golden files: within a temporal token the patch index is
//! row-major over the patch grid and the feature index is `((dt · ph + dy) · pw + dx) · c + ci`.
//! The frame mask scales each temporal token's patch embeddings before the CLS token and the
//! position embedding are added; a patch mask (`patch_selection`) scales each patch's, and a
//! patch whose entry is zero has no token at all, its pixels read as 0 by a spectral head over the
//! image's space ([`Pvt3::head_frames`]).

use candle_core::{Tensor, D};
use candle_nn::{linear, Init, Linear, Module, VarBuilder, VarMap};

use pvt3_spec::names;
use pvt3_spec::spectrum::frame_weights;
use pvt3_spec::spectrum::space::kept_pixels;

use crate::dropout::Dropout;
use crate::fused_block::pack;
use crate::fused_embed::{EmbedDims, EmbedOp};
use crate::head::Head;
use crate::spectrum::Spectrum;
use crate::transformer::{composed_ops, Transformer};
use crate::{Config, Result, Rng};

pub mod patches;
#[cfg(test)]
mod tests;

#[derive(Clone, Debug)]
pub struct Pvt3 {
    patch_embed: Linear,
    frame_mask: Tensor,
    /// `[num_patches]`, for a model with `patch_selection`.
    patch_mask: Option<Tensor>,
    pos_embed: Tensor,
    space_cls: Tensor,
    temporal_cls: Tensor,
    space: Transformer,
    temporal: Transformer,
    head: Head,
    /// The spectral head, when the configuration has one (`spectral_bands > 0`).
    spectrum: Option<Spectrum>,
    dropout: Dropout,
    cfg: Config,
}

impl Pvt3 {
    pub fn new(cfg: &Config, vb: VarBuilder) -> Result<Self> {
        cfg.validate()?;
        cfg.require_pvt3("the PVT³ network")?;
        let (t, n, d) = (cfg.time_tokens(), cfg.num_patches(), cfg.dim);
        let small = Init::Randn { mean: 0.0, stdev: 0.02 };
        Ok(Self {
            patch_embed: linear(cfg.patch_dim(), d, vb.pp(names::PATCH_EMBED))?,
            frame_mask: vb.get_with_hints(t, names::FRAME_MASK, Init::Const(1.0))?,
            patch_mask: match cfg.patch_selection() {
                true => Some(vb.get_with_hints(n, names::PATCH_MASK, Init::Const(1.0))?),
                false => None,
            },
            pos_embed: vb.get_with_hints((1, t, n + 1, d), names::POS_EMBED, small)?,
            space_cls: vb.get_with_hints((1, 1, d), names::SPACE_CLS, small)?,
            temporal_cls: vb.get_with_hints((1, 1, d), names::TEMPORAL_CLS, small)?,
            space: Transformer::new(cfg, cfg.space_depth, vb.pp(names::SPACE))?,
            temporal: Transformer::new(cfg, cfg.time_depth, vb.pp(names::TEMPORAL))?,
            head: Head::new(cfg, vb.clone())?,
            spectrum: if cfg.spectral_bands() > 0 { Some(Spectrum::new(cfg, vb.clone())?) } else { None },
            dropout: Dropout::new(cfg.dropout),
            cfg: cfg.clone(),
        })
    }

    /// A fresh model on the CPU with its variables in a new [`VarMap`], seeded by `seed`.
    pub fn init(cfg: &Config, seed: u64) -> Result<(Self, VarMap)> {
        crate::init::seeded(cfg, seed, Self::new)
    }

    pub fn config(&self) -> &Config {
        &self.cfg
    }

    /// Cuts `[b, h, w, (c,) t]` into `[b, time_tokens, num_patches, patch_dim]`.
    pub fn patchify(&self, x: &Tensor) -> Result<Tensor> {
        let c = &self.cfg;
        let b = c.check_input(x.dims())?;
        let (gh, gw, tt) = (c.height / c.patch_height, c.width / c.patch_width, c.time_tokens());
        let grid = x.reshape(vec![b, gh, c.patch_height, gw, c.patch_width, c.channels, tt, c.tubelet])?;
        // → [b, tt, gh, gw, tubelet, ph, pw, c]
        let tokens = grid.permute(vec![0, 6, 1, 3, 7, 2, 4, 5])?;
        Ok(tokens.reshape((b, tt, gh * gw, c.patch_dim()))?)
    }

    /// Logits `[b, classes]`. Pass an `rng` to train (dropout on), `None` to evaluate.
    pub fn forward(&self, x: &Tensor, rng: Option<&mut Rng>) -> Result<Tensor> {
        Ok(self.forward_pooled(x, None, rng)?.0)
    }

    /// The spectral head, if the model has one.
    pub fn spectrum(&self) -> Option<&Spectrum> {
        self.spectrum.as_ref()
    }

    /// Logits `[b, classes]` from the first `tokens` temporal tokens of each window alone: the
    /// touch so far, as the runtime's `Session::peek` answers it (the f64 reference's
    /// `forward_prefix`). The temporal transformer runs over the CLS token and those.
    pub fn forward_prefix(&self, x: &Tensor, tokens: usize, rng: Option<&mut Rng>) -> Result<Tensor> {
        Ok(self.forward_pooled(x, Some(tokens), rng)?.0)
    }

    /// Logits `[b, classes]` and the encoding `[b, dim]` the head reads them from (the temporal
    /// CLS token's output: what joint learning pulls together across sensors), of the whole
    /// window ([`Self::forward`]) or, with `tokens`, of its first `tokens` temporal tokens
    /// ([`Self::forward_prefix`]).
    pub fn forward_pooled(&self, x: &Tensor, tokens: Option<usize>, mut rng: Option<&mut Rng>) -> Result<(Tensor, Tensor)> {
        let sequence = self.sequence(x, rng.as_deref_mut())?;
        self.classify_prefix(x, &sequence, tokens.unwrap_or(self.cfg.time_tokens()), rng)
    }

    /// [`Self::forward_pooled`] of windows already cut into patches `[b, time_tokens,
    /// num_patches, patch_dim]` ([`Self::patchify`], [`patches::cut_into`]), for a model
    /// without a spectral head (which reads the frames themselves: [`Self::reads_patches`]).
    pub fn forward_pooled_patches(&self, patches: &Tensor, tokens: Option<usize>, mut rng: Option<&mut Rng>) -> Result<(Tensor, Tensor)> {
        if !self.reads_patches() {
            return Err(pvt3_spec::Error::Config("a model with a spectral head reads whole windows, not patches".into()).into());
        }
        let sequence = self.sequence_of_patches(patches, rng.as_deref_mut())?;
        self.classify_sequence(&sequence, tokens.unwrap_or(self.cfg.time_tokens()), rng)
    }

    /// Whether nothing but the patches is read of a window: no spectral head.
    pub fn reads_patches(&self) -> bool {
        self.spectrum.is_none()
    }

    /// Logits `[b, classes]` and the encoding `[b, dim]` of windows `x` from the first `tokens`
    /// temporal tokens of their sequence ([`Self::sequence`]): the temporal transformer over the
    /// CLS token and those, and the spectral head over their kept frames.
    pub fn classify_prefix(&self, x: &Tensor, sequence: &Tensor, tokens: usize, rng: Option<&mut Rng>) -> Result<(Tensor, Tensor)> {
        let (logits, pooled) = self.classify_sequence(sequence, tokens, rng)?;
        match &self.spectrum {
            Some(spectrum) => Ok(((logits + spectrum.forward(&self.head_frames(x)?, &self.frame_weights(tokens)?)?)?, pooled)),
            None => Ok((logits, pooled)),
        }
    }

    /// [`Self::classify_prefix`] without the spectral head's term.
    fn classify_sequence(&self, sequence: &Tensor, tokens: usize, rng: Option<&mut Rng>) -> Result<(Tensor, Tensor)> {
        self.cfg.check_prefix(tokens)?;
        let pooled = self.temporal.forward_cls(&sequence.narrow(1, 0, tokens + 1)?, rng)?;
        Ok((self.head.forward(&pooled)?, pooled))
    }

    /// What the spectral head reads of windows `x` `[b, h, w, (c,) t]`: for a head over the
    /// image's space of a model whose patch mask pruned patches, `x` with their pixels at 0
    /// (`pvt3_spec::spectrum::space::kept_pixels`); else `x`.
    pub fn head_frames(&self, x: &Tensor) -> Result<Tensor> {
        let c = &self.cfg;
        let Some(kept) = self.kept_patches()?.filter(|_| c.spectral_space()) else { return Ok(x.clone()) };
        let pixels: Vec<f32> = kept_pixels(c, &kept).into_iter().map(f32::from).collect();
        let shape: Vec<usize> = [1, c.height, c.width].into_iter().chain(std::iter::repeat_n(1, x.rank() - 3)).collect();
        Ok(x.broadcast_mul(&Tensor::from_vec(pixels, shape, x.device())?)?)
    }

    /// The patches the patch mask keeps (not zero), row-major over the grid, where it prunes any.
    fn kept_patches(&self) -> Result<Option<Vec<usize>>> {
        let Some(mask) = &self.patch_mask else { return Ok(None) };
        let values = mask.to_vec1::<f32>()?;
        Ok(values.contains(&0.0).then(|| (0..values.len()).filter(|p| values[*p] != 0.0).collect()))
    }

    /// The spectral head's weight of each frame (`pvt3_spec::spectrum::frame_weights`): the
    /// frames of the first `tokens` temporal tokens that the frame mask keeps (not zero).
    pub fn frame_weights(&self, tokens: usize) -> Result<Vec<f64>> {
        let mask = self.frame_mask.to_vec1::<f32>()?;
        Ok(frame_weights(self.cfg.frames, self.cfg.tubelet, tokens, |t| mask[t] != 0.0))
    }

    /// The temporal transformer's input `[b, 1 + time_tokens, dim]`: the CLS token, then each
    /// temporal token's spatial encoding.
    pub fn sequence(&self, x: &Tensor, rng: Option<&mut Rng>) -> Result<Tensor> {
        self.sequence_of_patches(&self.patchify(x)?, rng)
    }

    /// [`Self::sequence`] of windows cut into patches.
    fn sequence_of_patches(&self, patches: &Tensor, mut rng: Option<&mut Rng>) -> Result<Tensor> {
        let s = self.selection()?.dropped(self.cfg.patch_dropout(), rng.as_deref_mut())?;
        let tokens = if composed_ops() { self.embed_composed_as(patches, s)? } else { self.embed_as(patches, s)? };
        let (b, t, len, d) = tokens.dims4()?;
        let tokens = self.dropout.forward(&tokens, rng.as_deref_mut())?;
        let frames = self.space.forward_cls(&tokens.reshape((b * t, len, d))?, rng)?;
        let cls = self.temporal_cls.broadcast_as((b, 1, d))?;
        Ok(Tensor::cat(&[&cls, &frames.reshape((b, t, d))?], 1)?)
    }

    /// The patches of the spatial sequence: those the patch mask keeps (all, without one), each
    /// one's mask value, and the position embedding of the CLS token and those.
    fn selection(&self) -> Result<Selection> {
        let n = self.cfg.num_patches();
        let Some(mask) = &self.patch_mask else {
            let ones = Tensor::ones(n, candle_core::DType::F32, self.pos_embed.device())?;
            return Ok(Selection { kept: None, scale: ones, pos: self.pos_embed.clone() });
        };
        let Some(kept) = self.kept_patches()? else {
            return Ok(Selection { kept: None, scale: mask.clone(), pos: self.pos_embed.clone() });
        };
        let kept: Vec<u32> = kept.into_iter().map(|p| p as u32).collect();
        let rows: Vec<u32> = std::iter::once(0).chain(kept.iter().map(|p| p + 1)).collect();
        let device = mask.device();
        let kept = Tensor::new(kept, device)?;
        Ok(Selection {
            scale: mask.index_select(&kept, 0)?,
            pos: self.pos_embed.index_select(&Tensor::new(rows, device)?, 2)?,
            kept: Some(kept),
        })
    }

    /// The tokens of the spatial transformer, `[b, t, kept + 1, dim]`, from patches
    /// `[b, t, n, patch_dim]`: the patches the patch mask keeps, their embedding, × frame mask
    /// × patch mask, the CLS token in front, + position embedding, as one fused op.
    pub fn embed(&self, patches: &Tensor) -> Result<Tensor> {
        self.embed_as(patches, self.selection()?)
    }

    /// [`Self::embed`] of the patches `s` selects.
    fn embed_as(&self, patches: &Tensor, s: Selection) -> Result<Tensor> {
        let patches = s.take(patches)?;
        let (_, t, n, patch_dim) = patches.dims4()?;
        let bias = self.patch_embed.bias().expect("linear has a bias");
        let packed = pack([self.patch_embed.weight(), bias, &self.frame_mask, &self.space_cls, &s.pos, &s.scale])?;
        let dims = EmbedDims { tokens: t, patches: n, patch_dim, dim: self.cfg.dim };
        Ok(EmbedOp::new(dims).apply(&patches, &packed)?)
    }

    /// [`Self::embed`] composed of candle ops: the oracle of its tests.
    pub fn embed_composed(&self, patches: &Tensor) -> Result<Tensor> {
        self.embed_composed_as(patches, self.selection()?)
    }

    /// [`Self::embed_composed`] of the patches `s` selects.
    fn embed_composed_as(&self, patches: &Tensor, s: Selection) -> Result<Tensor> {
        let patches = s.take(patches)?;
        let (b, t, n, p) = patches.dims4()?;
        let d = self.cfg.dim;
        let embedded = self.patch_embed.forward(&patches.reshape((b * t * n, p))?)?.reshape((b, t, n, d))?;
        let embedded = embedded.broadcast_mul(&self.frame_mask.reshape((1, t, 1, 1))?)?;
        let embedded = embedded.broadcast_mul(&s.scale.reshape((1, 1, n, 1))?)?;
        let cls = self.space_cls.reshape((1, 1, 1, d))?.broadcast_as((b, t, 1, d))?;
        Ok(Tensor::cat(&[&cls, &embedded], 2)?.broadcast_add(&s.pos)?)
    }

    /// Class probabilities `[b, classes]` (evaluation mode).
    pub fn probabilities(&self, x: &Tensor) -> Result<Tensor> {
        Ok(candle_nn::ops::softmax(&self.forward(x, None)?, D::Minus1)?)
    }
}

/// The spatial sequence's patches as the patch mask selects them ([`Pvt3::selection`]).
struct Selection {
    /// The kept patches' indices; `None`: all of them.
    kept: Option<Tensor>,
    /// `[kept]`: each kept patch's mask value (ones without a mask).
    scale: Tensor,
    /// `[1, t, kept + 1, dim]`.
    pos: Tensor,
}

impl Selection {
    /// This selection less the patches a training step drops (`Config::patch_dropout`): each
    /// dropped with probability `p`, one uniform draw a patch in order, and where that leaves
    /// none, one kept at random. Unchanged without an `rng` (evaluation) or with `p` zero.
    fn dropped(self, p: f64, rng: Option<&mut Rng>) -> Result<Self> {
        let Some(rng) = rng.filter(|_| p > 0.0) else { return Ok(self) };
        let device = self.scale.device().clone();
        let all: Vec<u32> = match &self.kept {
            Some(kept) => kept.to_vec1()?,
            None => (0..self.scale.dim(0)? as u32).collect(),
        };
        let mut keep: Vec<u32> = (0..all.len() as u32).filter(|_| rng.uniform() as f64 >= p).collect();
        if keep.is_empty() {
            keep.push((rng.next_u64() % all.len() as u64) as u32);
        }
        let rows: Vec<u32> = std::iter::once(0).chain(keep.iter().map(|i| i + 1)).collect();
        let kept: Vec<u32> = keep.iter().map(|&i| all[i as usize]).collect();
        let keep = Tensor::new(keep, &device)?;
        Ok(Self {
            scale: self.scale.index_select(&keep, 0)?,
            pos: self.pos.index_select(&Tensor::new(rows, &device)?, 2)?,
            kept: Some(Tensor::new(kept, &device)?),
        })
    }

    /// The kept patches of `[b, t, n, patch_dim]`.
    fn take(&self, patches: &Tensor) -> Result<Tensor> {
        Ok(match &self.kept {
            Some(kept) => patches.index_select(kept, 2)?,
            None => patches.clone(),
        })
    }
}
