//! A sensor's network as training changes it ([`Net`]: its learner and weight average, and their
//! resume files), a model with its optimiser ([`Learner`]), and the training step: the
//! augmentations that act on a whole batch, the forward pass and its loss ([`super::loss`]),
//! backward, clipping and AdamW. A joint run's networks step together ([`step_together`]): one
//! backward pass through both losses and the distance between their encodings.

use std::path::Path;

use candle_core::backprop::GradStore;
use candle_core::{DType, Device, Tensor, Var};
use candle_nn::VarMap;
use pvt3_models::{Config, Model, Rng};
use pvt3_spec::names::Role;
use pvt3_spec::weights::Tensors;

use super::loss;
use crate::average::WeightAverage;
use crate::checkpoint::{self, Meta};
use crate::data::augment::{extrapolation, mixup};
use crate::optim::{is_weight_matrix, AdamW};
use crate::options::TrainOptions;
use crate::run_dir::Checkpoint;
use crate::{Error, Result};

/// What a sensor's training steps change: its learner and weight average.
pub(super) struct Net {
    pub(super) learner: Learner,
    pub(super) average: Option<WeightAverage>,
}

impl Net {
    pub(super) fn update_average(&mut self, step: usize) -> Result<()> {
        match &mut self.average {
            Some(average) => average.update(step),
            None => Ok(()),
        }
    }

    /// The weights, optimiser state and weight average of the checkpoint `dir` (a `last/`).
    pub(super) fn restore(&mut self, dir: &Path, step: usize) -> Result<()> {
        pvt3_models::weights::load_weights(&self.learner.varmap, &Checkpoint(dir).weights())?;
        self.learner.optimizer.load(&Checkpoint(dir).optimizer(), step)?;
        if let Some(average) = &mut self.average {
            average.load(&Checkpoint(dir).average())?;
        }
        Ok(())
    }

    /// Writes its resume state into `dir` (a `last/` being filled): the checkpoint of `meta`
    /// with its weights, and the optimiser state and weight average.
    pub(super) fn save_last(&self, dir: &Path, meta: &Meta) -> Result<()> {
        checkpoint::write_files(dir, &self.learner.varmap, meta)?;
        let files = Checkpoint(dir);
        self.learner.optimizer.save(&files.optimizer())?;
        if let Some(average) = &self.average {
            average.save(&files.average())?;
        }
        Ok(())
    }
}

/// A model with its optimiser: what one training step needs.
pub struct Learner {
    pub model: Model,
    pub varmap: VarMap,
    pub optimizer: AdamW,
    /// The selection masks, for the L1 penalty.
    masks: Vec<Tensor>,
    /// Mask variables and their 0/1 keep flags, re-applied after every step.
    held: Vec<(Var, Tensor)>,
    /// The weight matrices, for random pruning.
    matrices: Vec<Var>,
    /// Distillation (`--distill`): the runs whose answers join the targets.
    pub teachers: Option<crate::distill::Teachers>,
}

impl Learner {
    /// A seeded model, or one starting from `start` weights.
    pub fn new(config: &Config, opts: &TrainOptions, start: Option<&Tensors>) -> Result<Self> {
        let (model, varmap) = Model::init(config, opts.seed)?;
        if let Some(start) = start {
            pvt3_models::weights::set_vars(&varmap, start, Path::new("(start weights)"))?;
        }
        Self::with(model, varmap.clone(), &varmap, opts)
    }

    /// A seeded model whose variables under `prefix` are `shared`'s own (the same values, one
    /// storage): a joint run's other network sharing the run's temporal transformer
    /// (`--joint-share-temporal`). Its optimiser updates only its own variables; the shared ones
    /// are updated by `shared`'s learner, with the gradients of both networks' losses.
    pub fn sharing(config: &Config, opts: &TrainOptions, shared: &VarMap, prefix: &str) -> Result<Self> {
        let (_, seeded) = Model::init(config, opts.seed)?;
        let (own, varmap) = (VarMap::new(), VarMap::new());
        {
            let shared = shared.data().lock().expect("varmap lock poisoned");
            let mut all = varmap.data().lock().expect("varmap lock poisoned");
            for (name, var) in seeded.data().lock().expect("varmap lock poisoned").iter() {
                if !name.starts_with(prefix) {
                    own.data().lock().expect("varmap lock poisoned").insert(name.clone(), var.clone());
                    all.insert(name.clone(), var.clone());
                    continue;
                }
                match shared.get(name) {
                    Some(other) if other.shape() == var.shape() => all.insert(name.clone(), other.clone()),
                    _ => {
                        return Err(Error::Usage(format!(
                            "the two networks' `{name}` differ in shape: sharing their {prefix}* variables needs the same dim, depth, heads, dim_head and mlp_dim"
                        )))
                    }
                };
            }
        }
        let model = Model::new(config, candle_nn::VarBuilder::from_varmap(&varmap, DType::F32, &Device::Cpu))?;
        Self::with(model, varmap, &own, opts)
    }

    /// `model` over `varmap`, trained by an optimiser of the variables of `own`.
    fn with(model: Model, varmap: VarMap, own: &VarMap, opts: &TrainOptions) -> Result<Self> {
        let masks = vars_where(&varmap, is_mask).into_iter().map(|v| v.as_tensor().clone()).collect();
        let space_head = model.pvt3("").is_ok_and(|m| m.config().spectral_space());
        let optimizer = AdamW::new(own, opts.optimization.weight_decay, |n, v| match Role::of(n, v.rank()) {
            Role::Mask => opts.pruning.mask_lr,
            role if role.is_fitted() || (space_head && n.starts_with(pvt3_spec::names::SPECTRAL)) => 0.0,
            _ => 1.0,
        })?;
        let matrices = vars_where(own, is_weight_matrix);
        Ok(Self { model, varmap, optimizer, masks, held: Vec::new(), matrices, teachers: None })
    }

    /// From now on, entries of the variables `which` selects that are zero stay zero (masks after
    /// pruning; weight matrices after random weight pruning).
    pub fn hold_zeros(&mut self, which: fn(&str, &Var) -> bool) -> Result<()> {
        for v in vars_where(&self.varmap, which) {
            let keep = v.as_tensor().ne(0.0)?.to_dtype(DType::F32)?;
            self.held.push((v, keep));
        }
        Ok(())
    }

    /// One optimiser step on a batch of whole windows `x` (cut into patches here where
    /// [`Self::cuts`]): optional same-class extrapolation and mixup, forward with dropout,
    /// smoothed cross-entropy (plus the teachers' term and the L1 penalty on the masks), backward,
    /// gradient clipping, AdamW. Returns the loss and logits.
    pub fn step(&mut self, x: &Tensor, y: &Tensor, opts: &TrainOptions, lr: f64, rng: &mut Rng) -> Result<(f64, Tensor)> {
        let x = match self.cuts(opts) {
            Some(_) => self.model.pvt3("cut batches")?.patchify(x)?,
            None => x.clone(),
        };
        let batch = [(x, y.clone())];
        Ok(step_together(&mut [self], &batch, 0.0, opts, lr, rng)?.each.remove(0))
    }

    /// The configuration whose patches this learner's training batches come cut into
    /// ([`crate::data::windows::Samples::cut_batch`]), where nothing but PVT³'s embedding reads a
    /// window: no spectral head, no teachers and no extrapolation to the levels (which read the
    /// frames). `None`: whole windows.
    pub fn cuts(&self, opts: &TrainOptions) -> Option<&Config> {
        let pvt3 = self.model.pvt3("cut batches").ok()?;
        let levels = opts.augmentation.extrapolate > 0.0 && opts.augmentation.extrapolate_levels;
        (pvt3.reads_patches() && self.teachers.is_none() && !levels).then(|| pvt3.config())
    }

    /// A training step up to its loss, `x` the windows or, where [`Self::cuts`], their patches:
    /// with `pooled`, PVT³'s encoding too (joint learning).
    fn forward(&mut self, x: &Tensor, y: &Tensor, opts: &TrainOptions, pooled: bool, rng: &mut Rng) -> Result<Pass> {
        let mut saved = Vec::new();
        if opts.pruning.random_prune > 0.0 {
            let p = opts.pruning.random_prune as f32;
            for var in &self.matrices {
                let full = var.as_tensor().copy()?;
                let keep: Vec<f32> = (0..full.elem_count()).map(|_| if rng.uniform() < p { 0.0 } else { 1.0 }).collect();
                var.set(&(&full * Tensor::from_vec(keep, full.shape(), &Device::Cpu)?)?)?;
                saved.push(full);
            }
        }
        let extrapolated = if opts.augmentation.extrapolate > 0.0 {
            Some(extrapolation::extrapolate(x, y, opts.augmentation.extrapolate, opts.augmentation.extrapolate_levels, rng)?)
        } else {
            None
        };
        let x = extrapolated.as_ref().unwrap_or(x);
        let mixed = if opts.augmentation.mixup > 0.0 { Some(mixup::mix(x, y, opts.augmentation.mixup, rng)?) } else { None };
        let x = mixed.as_ref().map_or(x, |m| &m.x);
        let prefix = opts.prefix_training > 0.0 && rng.uniform() < opts.prefix_training as f32;
        let cut = self.cuts(opts).is_some();
        let (logits, extra, pooled) = if prefix || pooled || cut {
            let pvt3 = self.model.pvt3(if prefix { "--prefix-training" } else { "--joint" })?;
            let tokens = prefix.then(|| 1 + rng.below(pvt3.config().time_tokens()));
            let (logits, pooled) = match cut {
                true => pvt3.forward_pooled_patches(x, tokens, Some(rng))?,
                false => pvt3.forward_pooled(x, tokens, Some(rng))?,
            };
            (logits, None, Some(pooled))
        } else {
            let (logits, extra) = self.model.forward_with_loss(x, Some(rng))?;
            (logits, extra, None)
        };
        let mut loss = loss::smoothed_cross_entropy(&logits, y, opts.optimization.label_smoothing)?;
        if let Some(m) = &mixed {
            let partners = loss::smoothed_cross_entropy(&logits, &m.partner_labels, opts.optimization.label_smoothing)?;
            loss = ((loss * m.lambda)? + (partners * (1.0 - m.lambda))?)?;
        }
        if let Some(teachers) = &self.teachers {
            // The teachers read the whole window (mixed, if mixup mixed it) even where this
            // batch's answers are to its first tokens.
            let target = teachers.probabilities(x)?;
            loss = (loss + (crate::distill::soft_cross_entropy(&logits, &target)? * opts.distillation.weight)?)?;
        }
        if let Some(extra) = extra {
            loss = (loss + extra)?;
        }
        if opts.pruning.l1 > 0.0 && !self.masks.is_empty() {
            let flat: Vec<Tensor> = self.masks.iter().map(|m| m.abs()).collect::<candle_core::Result<_>>()?;
            loss = (loss + (Tensor::cat(&flat, 0)?.mean_all()? * opts.pruning.l1)?)?;
        }
        Ok(Pass { loss, logits, pooled, saved })
    }

    /// The rest of a step, once `grads` are known: the randomly pruned weights restored, the
    /// gradients clipped, AdamW, and held zeros kept.
    fn update(&mut self, grads: &GradStore, saved: &[Tensor], opts: &TrainOptions, lr: f64) -> Result<()> {
        for (var, full) in self.matrices.iter().zip(saved) {
            var.set(full)?;
        }
        let scale = if opts.optimization.clip_grad > 0.0 {
            (opts.optimization.clip_grad / self.optimizer.grad_norm(grads)?.max(1e-12)).min(1.0)
        } else {
            1.0
        };
        self.optimizer.step(grads, lr, scale)?;
        for (var, keep) in &self.held {
            var.set(&(var.as_tensor() * keep)?)?;
        }
        Ok(())
    }
}

/// A training step's forward pass: the loss, the logits and, when asked, the encoding.
struct Pass {
    loss: Tensor,
    logits: Tensor,
    pooled: Option<Tensor>,
    /// The full weight matrices, while random pruning has zeroed some of their entries.
    saved: Vec<Tensor>,
}

/// One optimiser step of every network in `learners`, each on its batch (`batches`, in the same
/// order): each network's loss, and with two networks (`--joint`) `pull` × the mean squared
/// error between their encodings ([`loss::encodings_apart`], measured at any `pull`), backward
/// once through the sum, and each network's own update.
pub fn step_together(
    learners: &mut [&mut Learner],
    batches: &[(Tensor, Tensor)],
    pull: f64,
    opts: &TrainOptions,
    lr: f64,
    rng: &mut Rng,
) -> Result<Stepped> {
    let joint = learners.len() > 1;
    let mut passes = Vec::with_capacity(learners.len());
    for (learner, (x, y)) in learners.iter_mut().zip(batches) {
        passes.push(learner.forward(x, y, opts, joint, rng)?);
    }
    let mut total = passes[0].loss.clone();
    for pass in &passes[1..] {
        total = (total + &pass.loss)?;
    }
    let apart = match passes.as_slice() {
        [a, b] => Some(loss::encodings_apart(a.pooled.as_ref().expect("asked for"), b.pooled.as_ref().expect("asked for"))?),
        _ => None,
    };
    if let Some(apart) = apart.as_ref().filter(|_| pull > 0.0) {
        total = (total + (apart * pull)?)?;
    }
    let grads = total.backward()?;
    for (learner, pass) in learners.iter_mut().zip(&passes) {
        learner.update(&grads, &pass.saved, opts, lr)?;
    }
    let each = passes.into_iter().map(|p| Ok((p.loss.to_scalar::<f32>()? as f64, p.logits))).collect::<Result<_>>()?;
    Ok(Stepped { each, apart: apart.map(|a| a.to_scalar::<f32>()).transpose()?.map(f64::from) })
}

/// What [`step_together`] returns.
pub struct Stepped {
    /// Each network's loss and logits, in the order of its learners.
    pub each: Vec<(f64, Tensor)>,
    /// The encodings' distance, in a joint step.
    pub apart: Option<f64>,
}

/// A selection mask (channel or frame).
pub(super) fn is_mask(name: &str, var: &Var) -> bool {
    Role::of(name, var.rank()) == Role::Mask
}

/// The variables `keep` selects, in name order.
fn vars_where(varmap: &VarMap, keep: fn(&str, &Var) -> bool) -> Vec<Var> {
    let vars = varmap.data().lock().expect("varmap lock poisoned");
    let mut names: Vec<&String> = vars.iter().filter(|(n, v)| keep(n, v)).map(|(n, _)| n).collect();
    names.sort();
    names.into_iter().map(|n| vars[n].clone()).collect()
}
