//! The training loop: AdamW with warm-up and cosine decay, label smoothing, gradient clipping,
//! optional gain, noise and time-shift augmentation, mixup ([`crate::mixup`]) and weight
//! averaging ([`crate::average`]), and epoch selection by validation accuracy. Every epoch appends
//! a line to `metrics.jsonl` and saves the run state under `last/`, so `--resume` continues an
//! interrupted run exactly; the best epoch's checkpoint is kept under `model/`.
//!
//! Run directory: `model/` (the checkpoint), `last/` (resume state), `metrics.jsonl`,
//! `result.json` (written when the run is complete).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use candle_core::backprop::GradStore;
use candle_core::{DType, Device, Tensor, Var, D};
use candle_nn::VarMap;
use indicatif::ProgressBar;
use pvt3_models::{Model, Config, Rng};
use pvt3_spec::names::Role;
use pvt3_spec::prune::PruneSpec;
use pvt3_spec::weights::Tensors;
use serde::{Deserialize, Serialize};

use crate::checkpoint::{self, nan_from_null, read_json, write_json, write_json_atomically};
use crate::data::Dataset;
use crate::data::augment::{augment, extrapolation, mixup};
use crate::data::windows::Samples;
use crate::joint::Partner;
use crate::metrics::EpochMetrics;
use crate::optim::{is_weight_matrix, AdamW};
use crate::options::TrainOptions;
use crate::run_dir::{Checkpoint, Run};
use crate::schedule::Schedule;
use crate::{Error, Result};
use sensor::{rows_by_class, Sensor, Tally, Validated};

/// The outcome of a finished run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunResult {
    /// `None`: a final model, which every touch trained.
    pub val_fold: Option<usize>,
    pub seed: u64,
    pub best_epoch: usize,
    /// NaN (`null`) where nothing validated or tested.
    #[serde(deserialize_with = "nan_from_null")]
    pub val_accuracy: f64,
    #[serde(deserialize_with = "nan_from_null")]
    pub test_accuracy: f64,
    pub epochs: usize,
    pub wall_seconds: f64,
}

/// What `last/state.json` remembers between epochs.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct RunState {
    epochs_done: usize,
    step: usize,
    rng: Rng,
    best: Option<Best>,
    /// A joint run's: the partner network's best epoch so far.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    partner_best: Option<Best>,
    wall_seconds: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
struct Best {
    epoch: usize,
    #[serde(deserialize_with = "nan_from_null")]
    val_accuracy: f64,
    #[serde(deserialize_with = "nan_from_null")]
    val_loss: f64,
    #[serde(deserialize_with = "nan_from_null")]
    test_accuracy: f64,
}

/// Everything a run needs besides its output directory.
#[derive(Clone)]
pub struct RunSpec<'a> {
    pub data: &'a Dataset,
    pub config: Config,
    /// The fold that validates (chooses the epoch); `None`: a final model, which every touch
    /// trains and whose last epoch is kept ([`crate::final_model`]).
    pub val_fold: Option<usize>,
    pub options: TrainOptions,
    pub classes: Vec<String>,
    /// Stop after this many epochs in this call, leaving the run to be resumed.
    pub pause_after: Option<usize>,
    /// Weights to start from instead of a seeded initialisation (fine-tuning).
    pub start: Option<Tensors>,
    /// The pruning that produced `start`, recorded in the provenance.
    pub pruning: Option<PruneSpec>,
    /// Joint learning (`--joint`): the second sensor trained beside.
    pub partner: Option<Partner<'a>>,
}

/// Cross-entropy against labels smoothed by `eps`.
fn smoothed_cross_entropy(logits: &Tensor, labels: &Tensor, eps: f64) -> Result<Tensor> {
    let nll = candle_nn::loss::cross_entropy(logits, labels)?;
    if eps == 0.0 {
        return Ok(nll);
    }
    let uniform = candle_nn::ops::log_softmax(logits, D::Minus1)?.mean_all()?.neg()?;
    Ok(((nll * (1.0 - eps))? + (uniform * eps)?)?)
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
        let optimizer = AdamW::new(own, opts.weight_decay, |n, v| if is_mask(n, v) { opts.mask_lr } else { 1.0 })?;
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

    /// One optimiser step on a batch: optional same-class extrapolation and mixup, forward with
    /// dropout, smoothed cross-entropy (plus the teachers' term and the L1 penalty on the masks), backward, gradient
    /// clipping, AdamW. Returns the loss and logits.
    pub fn step(&mut self, x: &Tensor, y: &Tensor, opts: &TrainOptions, lr: f64, rng: &mut Rng) -> Result<(f64, Tensor)> {
        let pass = self.forward(x, y, opts, false, rng)?;
        let grads = pass.loss.backward()?;
        self.update(&grads, &pass.saved, opts, lr)?;
        Ok((pass.loss.to_scalar::<f32>()? as f64, pass.logits))
    }

    /// A training step up to its loss: with `pooled`, PVT³'s encoding too (joint learning).
    fn forward(&mut self, x: &Tensor, y: &Tensor, opts: &TrainOptions, pooled: bool, rng: &mut Rng) -> Result<Pass> {
        let mut saved = Vec::new();
        if opts.random_prune > 0.0 {
            let p = opts.random_prune as f32;
            for var in &self.matrices {
                let full = var.as_tensor().copy()?;
                let keep: Vec<f32> = (0..full.elem_count()).map(|_| if rng.uniform() < p { 0.0 } else { 1.0 }).collect();
                var.set(&(&full * Tensor::from_vec(keep, full.shape(), &Device::Cpu)?)?)?;
                saved.push(full);
            }
        }
        let extrapolated = if opts.extrapolate > 0.0 {
            Some(extrapolation::extrapolate(x, y, opts.extrapolate, opts.extrapolate_levels, rng)?)
        } else {
            None
        };
        let x = extrapolated.as_ref().unwrap_or(x);
        let mixed = if opts.mixup > 0.0 { Some(mixup::mix(x, y, opts.mixup, rng)?) } else { None };
        let x = mixed.as_ref().map_or(x, |m| &m.x);
        let prefix = opts.prefix_training > 0.0 && rng.uniform() < opts.prefix_training as f32;
        let (logits, extra, pooled) = if prefix || pooled {
            let pvt3 = self.model.pvt3(if prefix { "--prefix-training" } else { "--joint" })?;
            let tokens = prefix.then(|| 1 + rng.below(pvt3.config().time_tokens()));
            let (logits, pooled) = pvt3.forward_pooled(x, tokens, Some(rng))?;
            (logits, None, Some(pooled))
        } else {
            let (logits, extra) = self.model.forward_with_loss(x, Some(rng))?;
            (logits, extra, None)
        };
        let mut loss = smoothed_cross_entropy(&logits, y, opts.label_smoothing)?;
        if let Some(m) = &mixed {
            let partners = smoothed_cross_entropy(&logits, &m.partner_labels, opts.label_smoothing)?;
            loss = ((loss * m.lambda)? + (partners * (1.0 - m.lambda))?)?;
        }
        if let Some(teachers) = &self.teachers {
            // The teachers read the whole window (mixed, if mixup mixed it) even where this
            // batch's answers are to its first tokens.
            let target = teachers.probabilities(x)?;
            loss = (loss + (crate::distill::soft_cross_entropy(&logits, &target)? * opts.distill_weight)?)?;
        }
        if let Some(extra) = extra {
            loss = (loss + extra)?;
        }
        if opts.l1 > 0.0 && !self.masks.is_empty() {
            let flat: Vec<Tensor> = self.masks.iter().map(|m| m.abs()).collect::<candle_core::Result<_>>()?;
            loss = (loss + (Tensor::cat(&flat, 0)?.mean_all()? * opts.l1)?)?;
        }
        Ok(Pass { loss, logits, pooled, saved })
    }

    /// The rest of a step, once `grads` are known: the randomly pruned weights restored, the
    /// gradients clipped, AdamW, and held zeros kept.
    fn update(&mut self, grads: &GradStore, saved: &[Tensor], opts: &TrainOptions, lr: f64) -> Result<()> {
        for (var, full) in self.matrices.iter().zip(saved) {
            var.set(full)?;
        }
        let scale = if opts.clip_grad > 0.0 { (opts.clip_grad / self.optimizer.grad_norm(grads)?.max(1e-12)).min(1.0) } else { 1.0 };
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

/// One step of two sensors' networks trained together (`--joint`) on batches of the same labels:
/// each network's own loss, plus `weight` × the mean squared error between their encodings,
/// backward once, and each network's own update. Returns both passes' losses and logits, and the
/// encodings' mean squared error (measured at any weight).
fn joint_step(
    a: &mut Learner,
    b: &mut Learner,
    [(xa, ya), (xb, yb)]: [(&Tensor, &Tensor); 2],
    weight: f64,
    opts: &TrainOptions,
    lr: f64,
    rng: &mut Rng,
) -> Result<([(f64, Tensor); 2], f64)> {
    let pa = a.forward(xa, ya, opts, true, rng)?;
    let pb = b.forward(xb, yb, opts, true, rng)?;
    let (ea, eb) = (pa.pooled.as_ref().expect("asked for"), pb.pooled.as_ref().expect("asked for"));
    let apart = (ea - eb)?.sqr()?.mean_all()?;
    let mut total = (&pa.loss + &pb.loss)?;
    if weight > 0.0 {
        total = (total + (&apart * weight)?)?;
    }
    let grads = total.backward()?;
    a.update(&grads, &pa.saved, opts, lr)?;
    b.update(&grads, &pb.saved, opts, lr)?;
    let losses = [(pa.loss.to_scalar::<f32>()? as f64, pa.logits), (pb.loss.to_scalar::<f32>()? as f64, pb.logits)];
    Ok((losses, apart.to_scalar::<f32>()? as f64))
}

/// A selection mask (channel or frame).
fn is_mask(name: &str, var: &Var) -> bool {
    Role::of(name, var.rank()) == Role::Mask
}

/// The variables `keep` selects, in name order.
fn vars_where(varmap: &VarMap, keep: fn(&str, &Var) -> bool) -> Vec<Var> {
    let vars = varmap.data().lock().expect("varmap lock poisoned");
    let mut names: Vec<&String> = vars.iter().filter(|(n, v)| keep(n, v)).map(|(n, _)| n).collect();
    names.sort();
    names.into_iter().map(|n| vars[n].clone()).collect()
}

/// Trains one split into `out`; with `resume`, continues the run found there. `None` means the
/// run paused (see [`RunSpec::pause_after`]) and can be resumed. With a partner (`--joint`), its
/// network trains beside, into the run directory `out/partner/` (its resume state inside
/// `out/last/`, so that the two resume together).
pub fn train(spec: &RunSpec, out: &Path, resume: bool, bar: &ProgressBar) -> Result<Option<RunResult>> {
    let run_dir = Run(out);
    let result_path = run_dir.result();
    let last = run_dir.last();
    let resumable = checkpoint::existing_dir(&last);
    if resume && result_path.exists() {
        check_resumed_split(spec, &run_dir.model())?;
        return read_json(&result_path).map(Some);
    }
    if !resume && (resumable.is_some() || result_path.exists()) {
        return Err(Error::Usage(format!(
            "{} already holds a run; pass --resume to continue it, or choose another output directory",
            out.display()
        )));
    }
    let (mut spec_options, mut config) = (spec.options.clone(), spec.config.clone());
    let mut state = None;
    if let (true, Some(dir)) = (resume, &resumable) {
        // A resumed run keeps the configuration and options it started with.
        check_resumed_split(spec, dir)?;
        let (_, meta) = checkpoint::load_meta(dir)?;
        config = meta.config;
        spec_options = meta.provenance.options;
        state = Some((dir.clone(), read_json::<RunState>(&Checkpoint(dir).state())?));
    }
    let opts = &spec_options;
    let mut main = Sensor::new(spec.data, config, spec.classes.clone(), (spec.val_fold, opts), spec.start.as_ref(), None)?;
    let partner_opts = spec.partner.as_ref().map(|_| Partner::options(opts, spec.data));
    let mut partner = match (&spec.partner, &partner_opts) {
        (Some(p), Some(po)) => {
            p.check(main.data, &main.config, &main.classes, opts)?;
            let share = opts.joint.as_ref().is_some_and(|j| j.share_temporal).then_some(&main.net.learner.varmap);
            Some(Sensor::new(p.data, p.config.clone(), p.classes.clone(), (spec.val_fold, po), None, share)?)
        }
        _ => None,
    };
    if let Some(teachers) = &opts.distill {
        main.net.learner.teachers = Some(crate::distill::Teachers::load(
            Path::new(teachers),
            (spec.val_fold, &main.data.trained_on()),
            &main.normalization,
            &main.classes,
            out,
        )?);
    }
    let partner_dir = run_dir.partner();
    std::fs::create_dir_all(out).map_err(Error::io(out))?;
    if partner.is_some() {
        std::fs::create_dir_all(&partner_dir).map_err(Error::io(&partner_dir))?;
    }
    let steps_per_epoch = main.split.train.len().div_ceil(opts.batch_size);
    let schedule = Schedule {
        peak: opts.lr,
        floor: opts.lr * opts.lr_floor,
        warmup_steps: opts.warmup_epochs * steps_per_epoch,
        total_steps: opts.epochs * steps_per_epoch,
    };
    let mut run = match state {
        Some((dir, st)) => {
            main.restore(&dir, st.step)?;
            truncate_metrics(&run_dir.metrics(), st.epochs_done)?;
            if let Some(p) = &mut partner {
                p.restore(&Checkpoint(&dir).partner(), st.step)?;
                truncate_metrics(&Run(&partner_dir).metrics(), st.epochs_done)?;
            }
            st
        }
        None => {
            if spec.start.is_none() {
                for sensor in std::iter::once(&main).chain(partner.as_ref()) {
                    crate::spectrum_fit::fit(&sensor.net.learner.model, &sensor.net.learner.varmap, &sensor.train_set)?;
                }
            }
            let _ = std::fs::remove_file(run_dir.metrics());
            let _ = std::fs::remove_file(Run(&partner_dir).metrics());
            RunState {
                epochs_done: 0,
                step: 0,
                rng: Rng::new(opts.seed.wrapping_add(1)),
                best: None,
                partner_best: None,
                wall_seconds: 0.0,
            }
        }
    };

    for sensor in std::iter::once(&mut main).chain(partner.as_mut()) {
        if opts.hold_pruned {
            sensor.net.learner.hold_zeros(is_mask)?;
        }
        if opts.hold_zero_weights {
            sensor.net.learner.hold_zeros(is_weight_matrix)?;
        }
    }
    bar.set_length((opts.epochs * steps_per_epoch) as u64);
    bar.set_position((run.epochs_done * steps_per_epoch) as u64);
    let open_log = |path: PathBuf| std::fs::OpenOptions::new().create(true).append(true).open(&path).map_err(Error::io(&path));
    let mut log = open_log(run_dir.metrics())?;
    let mut partner_log = partner.as_ref().map(|_| open_log(Run(&partner_dir).metrics())).transpose()?;
    let first_epoch = run.epochs_done + 1;
    for epoch in first_epoch..=opts.epochs {
        if spec.pause_after.is_some_and(|p| epoch - first_epoch >= p) {
            return Ok(None);
        }
        let started = Instant::now();
        let cropped = main.epoch_windows(opts, &mut run.rng);
        let partner_cropped = partner.as_ref().and_then(|p| p.epoch_windows(opts, &mut run.rng));
        let Sensor { net, train_set, normalization, .. } = &mut main;
        let train_set = cropped.as_ref().unwrap_or(train_set);
        // A joint run's other sensor: its windows this epoch, each class's rows among them, its network.
        let mut other = partner.as_mut().map(|p| {
            let set = partner_cropped.as_ref().unwrap_or(&p.train_set);
            (set, rows_by_class(set, p.config.classes), &p.normalization, &mut p.net)
        });
        let mut order: Vec<usize> = (0..train_set.len()).collect();
        run.rng.shuffle(&mut order);
        let (mut tally, mut partner_tally) = (Tally::default(), Tally::default());
        let mut lr = schedule.at(run.step);
        for rows in order.chunks(opts.batch_size) {
            let rng = &mut run.rng;
            let (x, y) = train_set.batch(rows, |s| augment(s, normalization, opts, rng))?;
            lr = schedule.at(run.step);
            match (&mut other, &opts.joint) {
                (Some((set, same_class, norm, other_net)), Some(joint)) => {
                    // Each touch's partner: a touch of its class among the other sensor's training windows.
                    let pairs = crate::joint::draw_partners(rows.iter().map(|&r| train_set.labels[r]), same_class, &mut run.rng)?;
                    let rng = &mut run.rng;
                    let (xb, yb) = set.batch(&pairs, |s| augment(s, norm, opts, rng))?;
                    let weight = if epoch > joint.after_epochs { joint.weight } else { 0.0 };
                    let ([(loss, logits), (partner_loss, partner_logits)], apart) =
                        joint_step(&mut net.learner, &mut other_net.learner, [(&x, &y), (&xb, &yb)], weight, opts, lr, &mut run.rng)?;
                    tally.add(loss, &logits, &y, rows.len())?;
                    partner_tally.add(partner_loss, &partner_logits, &yb, rows.len())?;
                    for t in [&mut tally, &mut partner_tally] {
                        *t.apart.get_or_insert(0.0) += apart * rows.len() as f64;
                    }
                    other_net.update_average(run.step + 1)?;
                }
                _ => {
                    let (loss, logits) = net.learner.step(&x, &y, opts, lr, &mut run.rng)?;
                    tally.add(loss, &logits, &y, rows.len())?;
                }
            }
            run.step += 1;
            net.update_average(run.step)?;
            bar.inc(1);
        }
        let n = train_set.len() as f64;
        // With weight averaging, the average is what is evaluated, selected and checkpointed.
        let (val_fold, pruning) = (spec.val_fold, &spec.pruning);
        let val = main.validate(epoch, &mut run.best, &run_dir.model(), (val_fold, opts, pruning))?;
        let partner_val = match (&mut partner, &partner_opts) {
            (Some(p), Some(po)) => Some(p.validate(epoch, &mut run.partner_best, &Run(&partner_dir).model(), (val_fold, po, pruning))?),
            _ => None,
        };
        let seconds = started.elapsed().as_secs_f64();
        run.wall_seconds += seconds;
        run.epochs_done = epoch;
        let line = |t: &Tally, v: &Validated| EpochMetrics {
            epoch,
            lr,
            train_loss: t.loss / n,
            train_accuracy: t.correct as f64 / n,
            val_loss: v.loss,
            val_accuracy: v.accuracy,
            test_accuracy: v.test_accuracy,
            seconds,
            encodings_apart: t.apart.map(|a| a / n),
        };
        checkpoint::replace_dir(&last, |dir| {
            main.save_last(dir, &main.meta(val_fold, opts, pruning, epoch, val.accuracy, None))?;
            if let (Some(p), Some(po), Some(pv)) = (&partner, &partner_opts, &partner_val) {
                let sub = Checkpoint(dir).partner();
                std::fs::create_dir_all(&sub).map_err(Error::io(&sub))?;
                p.save_last(&sub, &p.meta(val_fold, po, pruning, epoch, pv.accuracy, None))?;
            }
            write_json(&Checkpoint(dir).state(), &run)
        })?;
        writeln!(log, "{}", serde_json::to_string(&line(&tally, &val)).expect("plain data")).map_err(Error::io(out))?;
        crate::plot::curves::write_run(out)?;
        if let (Some(plog), Some(pv)) = (&mut partner_log, &partner_val) {
            writeln!(plog, "{}", serde_json::to_string(&line(&partner_tally, pv)).expect("plain data")).map_err(Error::io(&partner_dir))?;
            crate::plot::curves::write_run(&partner_dir)?;
        }
        let best = run.best.as_ref().expect("set after the first epoch");
        bar.set_message(format!(
            "epoch {epoch}/{} loss {:.3} train {:.3} val {:.3} (best {:.3} @ {})",
            opts.epochs,
            tally.loss / n,
            tally.correct as f64 / n,
            val.accuracy,
            best.val_accuracy,
            best.epoch
        ));
    }
    let result = |best: &Option<Best>| -> Result<RunResult> {
        let best = best.clone().ok_or_else(|| Error::Usage("no epoch was trained (epochs = 0)".into()))?;
        Ok(RunResult {
            val_fold: spec.val_fold,
            seed: opts.seed,
            best_epoch: best.epoch,
            val_accuracy: best.val_accuracy,
            test_accuracy: best.test_accuracy,
            epochs: opts.epochs,
            wall_seconds: run.wall_seconds,
        })
    };
    // The partner's run finishes first: a run with its result.json is a finished joint run.
    if let Some(p) = &partner {
        let partner_result = result(&run.partner_best)?;
        calibrate_stopping(&Run(&partner_dir).model(), &p.val_set)?;
        write_json(&Run(&partner_dir).result(), &partner_result)?;
    }
    let result = result(&run.best)?;
    calibrate_stopping(&run_dir.model(), &main.val_set)?;
    write_json(&result_path, &result)?;
    Ok(Some(result))
}

/// Refuses to continue the run whose checkpoint is `dir` (and its partner's) on data split
/// otherwise than it recorded, naming what differs (another file, another seed's folds, other
/// held-out levels).
fn check_resumed_split(spec: &RunSpec, dir: &Path) -> Result<()> {
    let partner = spec.partner.as_ref().map(|p| (p.data, Checkpoint(dir).partner()));
    for (data, checkpoint) in std::iter::once((spec.data, dir.to_path_buf())).chain(partner) {
        let Some(existing) = checkpoint::existing_dir(&checkpoint) else { continue };
        let (_, meta) = checkpoint::load_meta(&existing)?;
        if let Some(recorded) = &meta.provenance.trained_on {
            let held = |h: Option<&crate::data::HoldOut>| h.map_or("no held-out levels".to_string(), |h| format!("held out {h}"));
            data.check_split(
                recorded,
                &format!(
                    "the run in {} (seed {}, {}; this command: {})",
                    existing.display(),
                    meta.provenance.seed,
                    held(meta.provenance.held_out.as_ref()),
                    held(data.held_out.as_ref())
                ),
            )?;
        }
    }
    Ok(())
}

/// Calibrates the stopping rule of provisional answers ([`crate::anytime`]) for the PVT³
/// checkpoint in `dir` on the validation samples, into its provenance (which the exporter
/// writes into the file). Other networks give no provisional answers, and a run with nothing to
/// validate is calibrated by no one here.
fn calibrate_stopping(dir: &Path, val_set: &Samples) -> Result<()> {
    if val_set.is_empty() {
        // A final model takes its cross-validation's rule (`crate::final_model`).
        return Ok(());
    }
    let (mut meta, model, _) = checkpoint::load(dir)?;
    let Some(pvt3) = crate::anytime::answering(&model) else { return Ok(()) };
    meta.provenance.stopping = Some(crate::anytime::prefixes(pvt3, val_set)?.calibrate());
    write_json_atomically(&Checkpoint(dir).provenance(), &meta.provenance)
}

/// Keeps the first `epochs` lines of a metrics log (a crash may have left one more).
fn truncate_metrics(path: &Path, epochs: usize) -> Result<()> {
    let Ok(text) = std::fs::read_to_string(path) else {
        return Ok(());
    };
    let kept: String = text.lines().take(epochs).map(|l| format!("{l}\n")).collect();
    std::fs::write(path, kept).map_err(Error::io(path))
}

mod sensor;

#[cfg(test)]
pub(crate) mod tests;
