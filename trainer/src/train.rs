//! The training loop: AdamW with warm-up and cosine decay, label smoothing, gradient clipping,
//! optional gain, noise and time-shift augmentation, mixup ([`crate::mixup`]) and weight
//! averaging ([`crate::average`]), and epoch selection by validation accuracy. Every epoch appends
//! a line to `metrics.jsonl` and saves the run state under `last/`, so `--resume` continues an
//! interrupted run exactly; the best epoch's checkpoint is kept under `model/`.
//!
//! Run directory: `model/` (the checkpoint), `last/` (resume state), `metrics.jsonl`,
//! `result.json` (written when the run is complete).

use std::io::Write;
use std::path::Path;
use std::time::Instant;

use candle_core::{DType, Device, Tensor, Var, D};
use candle_nn::VarMap;
use indicatif::ProgressBar;
use pvt3_models::{Classifier, Config, Rng};
use pvt3_spec::names::Role;
use pvt3_spec::prune::PruneSpec;
use pvt3_spec::weights::Tensors;
use serde::{Deserialize, Serialize};

use crate::average::WeightAverage;
use crate::checkpoint::{self, read_json, write_json, write_json_atomically, Meta, Provenance};
use crate::data::{Dataset, Split};
use crate::evaluate::{evaluate, log_uniform_factor, Samples};
use crate::metrics::EpochMetrics;
use crate::normalization::Normalization;
use crate::optim::{is_weight_matrix, AdamW};
use crate::options::TrainOptions;
use crate::run_dir::{Checkpoint, Run};
use crate::schedule::Schedule;
use crate::{Error, Result};

/// The outcome of a finished run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunResult {
    pub val_fold: usize,
    pub seed: u64,
    pub best_epoch: usize,
    pub val_accuracy: f64,
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
    wall_seconds: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
struct Best {
    epoch: usize,
    val_accuracy: f64,
    val_loss: f64,
    test_accuracy: f64,
}

/// Everything a run needs besides its output directory.
#[derive(Clone)]
pub struct RunSpec<'a> {
    pub data: &'a Dataset,
    pub config: Config,
    pub val_fold: usize,
    pub options: TrainOptions,
    pub classes: Vec<String>,
    /// Stop after this many epochs in this call, leaving the run to be resumed.
    pub pause_after: Option<usize>,
    /// Weights to start from instead of a seeded initialisation (fine-tuning).
    pub start: Option<Tensors>,
    /// The pruning that produced `start`, recorded in the provenance.
    pub pruning: Option<PruneSpec>,
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
    pub model: Classifier,
    pub varmap: VarMap,
    pub optimizer: AdamW,
    /// The selection masks, for the L1 penalty.
    masks: Vec<Tensor>,
    /// Mask variables and their 0/1 keep flags, re-applied after every step.
    held: Vec<(Var, Tensor)>,
    /// The weight matrices, for random pruning.
    matrices: Vec<Var>,
}

impl Learner {
    /// A seeded model, or one starting from `start` weights.
    pub fn new(config: &Config, opts: &TrainOptions, start: Option<&Tensors>) -> Result<Self> {
        let (model, varmap) = Classifier::init(config, opts.seed)?;
        if let Some(start) = start {
            pvt3_models::weights::set_vars(&varmap, start, Path::new("(start weights)"))?;
        }
        let masks = vars_where(&varmap, is_mask).into_iter().map(|v| v.as_tensor().clone()).collect();
        let optimizer = AdamW::new(&varmap, opts.weight_decay, |n, v| if is_mask(n, v) { opts.mask_lr } else { 1.0 })?;
        let matrices = vars_where(&varmap, is_weight_matrix);
        Ok(Self { model, varmap, optimizer, masks, held: Vec::new(), matrices })
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

    /// One optimiser step on a batch: optional mixup, forward with dropout, smoothed cross-entropy
    /// (plus the L1 penalty on the masks), backward, gradient clipping, AdamW. Returns the loss and
    /// logits.
    pub fn step(&mut self, x: &Tensor, y: &Tensor, opts: &TrainOptions, lr: f64, rng: &mut Rng) -> Result<(f64, Tensor)> {
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
        let mixed = if opts.mixup > 0.0 { Some(crate::mixup::mix(x, y, opts.mixup, rng)?) } else { None };
        let x = mixed.as_ref().map_or(x, |m| &m.x);
        let (logits, extra) = if opts.prefix_training > 0.0 && rng.uniform() < opts.prefix_training as f32 {
            let pvt3 = self.model.pvt3("--prefix-training")?;
            let tokens = 1 + rng.below(pvt3.config().time_tokens());
            (pvt3.forward_prefix(x, tokens, Some(rng))?, None)
        } else {
            self.model.forward_with_loss(x, Some(rng))?
        };
        let mut loss = smoothed_cross_entropy(&logits, y, opts.label_smoothing)?;
        if let Some(m) = &mixed {
            let partners = smoothed_cross_entropy(&logits, &m.partner_labels, opts.label_smoothing)?;
            loss = ((loss * m.lambda)? + (partners * (1.0 - m.lambda))?)?;
        }
        if let Some(extra) = extra {
            loss = (loss + extra)?;
        }
        if opts.l1 > 0.0 && !self.masks.is_empty() {
            let flat: Vec<Tensor> = self.masks.iter().map(|m| m.abs()).collect::<candle_core::Result<_>>()?;
            loss = (loss + (Tensor::cat(&flat, 0)?.mean_all()? * opts.l1)?)?;
        }
        let grads = loss.backward()?;
        for (var, full) in self.matrices.iter().zip(&saved) {
            var.set(full)?;
        }
        let scale = if opts.clip_grad > 0.0 { (opts.clip_grad / self.optimizer.grad_norm(&grads)?.max(1e-12)).min(1.0) } else { 1.0 };
        self.optimizer.step(&grads, lr, scale)?;
        for (var, keep) in &self.held {
            var.set(&(var.as_tensor() * keep)?)?;
        }
        Ok((loss.to_scalar::<f32>()? as f64, logits))
    }
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

fn augment(sample: &mut [f32], norm: &Normalization, opts: &TrainOptions, rng: &mut Rng) {
    let frames = norm.frames;
    if opts.aug_scale > 0.0 {
        // The raw readings times k, in normalised units: k z + (k - 1) mean / std, per channel.
        let k = log_uniform_factor(opts.aug_scale, rng) as f32;
        for (row, (m, s)) in sample.chunks_mut(frames).zip(norm.mean.iter().zip(&norm.std)) {
            let lift = (k - 1.0) * m / s;
            row.iter_mut().for_each(|v| *v = k * *v + lift);
        }
    }
    if opts.aug_vibration > 0.0 {
        // Each channel's variation about its mean over the window, times one factor for all.
        let k = log_uniform_factor(opts.aug_vibration, rng) as f32;
        for row in sample.chunks_mut(frames) {
            let mean = row.iter().sum::<f32>() / frames as f32;
            row.iter_mut().for_each(|v| *v = mean + k * (*v - mean));
        }
    }
    if opts.aug_shift > 0 {
        let span = 2 * opts.aug_shift + 1;
        let shift = rng.below(span) as isize - opts.aug_shift as isize;
        let last = frames as isize - 1;
        for row in sample.chunks_mut(frames) {
            let original = row.to_vec();
            for (t, v) in row.iter_mut().enumerate() {
                *v = original[(t as isize - shift).clamp(0, last) as usize];
            }
        }
    }
    let gain = 1.0 + opts.aug_gain as f32 * (2.0 * rng.uniform() - 1.0);
    let noise = opts.aug_noise as f32;
    for v in sample.iter_mut() {
        *v = *v * gain + if noise > 0.0 { noise * rng.normal() } else { 0.0 };
    }
}

/// Trains one split into `out`; with `resume`, continues the run found there. `None` means the
/// run paused (see [`RunSpec::pause_after`]) and can be resumed.
pub fn train(spec: &RunSpec, out: &Path, resume: bool, bar: &ProgressBar) -> Result<Option<RunResult>> {
    let run_dir = Run(out);
    let result_path = run_dir.result();
    let last = run_dir.last();
    let resumable = checkpoint::existing_dir(&last);
    if resume && result_path.exists() {
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
        let (_, meta) = checkpoint::load_meta(dir)?;
        config = meta.config;
        spec_options = meta.provenance.options;
        state = Some((dir.clone(), read_json::<RunState>(&Checkpoint(dir).state())?));
    }
    let opts = &spec_options;
    spec.data.check_fits(&config)?;
    let split: Split = spec.data.split(spec.val_fold)?;
    let normalization = crate::normalization::fit(spec.data, &split.train, config.frames);
    // Every training touch read as its evaluation windows: what fits the spectral head's
    // standardisation, and each epoch's batches when every touch is one window long. A longer
    // touch gives each epoch one window drawn at random (`Samples::cropped`).
    let train_set = Samples::new(spec.data, &split.train, &normalization);
    let crops = opts.aug_stretch > 0.0 || split.train.iter().any(|&i| spec.data.lengths[i] > config.frames);
    let val_set = Samples::new(spec.data, &split.val, &normalization);
    let test_set = Samples::new(spec.data, &split.test, &normalization);

    std::fs::create_dir_all(out).map_err(Error::io(out))?;
    let mut learner = Learner::new(&config, opts, spec.start.as_ref())?;
    let mut average = if opts.ema > 0.0 { Some(WeightAverage::new(&learner.varmap, opts.ema)?) } else { None };
    let steps_per_epoch = split.train.len().div_ceil(opts.batch_size);
    let schedule = Schedule {
        peak: opts.lr,
        floor: opts.lr * opts.lr_floor,
        warmup_steps: opts.warmup_epochs * steps_per_epoch,
        total_steps: opts.epochs * steps_per_epoch,
    };
    let mut run = match state {
        Some((dir, st)) => {
            pvt3_models::weights::load_weights(&learner.varmap, &Checkpoint(&dir).weights())?;
            learner.optimizer.load(&Checkpoint(&dir).optimizer(), st.step)?;
            if let Some(average) = &mut average {
                average.load(&Checkpoint(&dir).average())?;
            }
            truncate_metrics(&run_dir.metrics(), st.epochs_done)?;
            st
        }
        None => {
            if spec.start.is_none() {
                crate::spectrum_fit::fit(&learner.model, &learner.varmap, &train_set)?;
            }
            let _ = std::fs::remove_file(run_dir.metrics());
            RunState { epochs_done: 0, step: 0, rng: Rng::new(opts.seed.wrapping_add(1)), best: None, wall_seconds: 0.0 }
        }
    };

    let meta_for = |epoch: usize, val_accuracy: f64, test_accuracy: Option<f64>| Meta {
        config: config.clone(),
        normalization: normalization.clone(),
        classes: spec.classes.clone(),
        provenance: Provenance {
            pvt3_version: env!("CARGO_PKG_VERSION").to_string(),
            data: spec.data.path.display().to_string(),
            val_fold: spec.val_fold,
            seed: opts.seed,
            epoch,
            val_accuracy,
            test_accuracy,
            options: opts.clone(),
            pruning: spec.pruning.clone(),
            held_out: spec.data.held_out.clone(),
            reading: spec.data.reading,
            stopping: None,
        },
    };

    if opts.hold_pruned {
        learner.hold_zeros(is_mask)?;
    }
    if opts.hold_zero_weights {
        learner.hold_zeros(is_weight_matrix)?;
    }
    bar.set_length((opts.epochs * steps_per_epoch) as u64);
    bar.set_position((run.epochs_done * steps_per_epoch) as u64);
    let mut log = std::fs::OpenOptions::new().create(true).append(true).open(run_dir.metrics()).map_err(Error::io(out))?;
    let first_epoch = run.epochs_done + 1;
    for epoch in first_epoch..=opts.epochs {
        if spec.pause_after.is_some_and(|p| epoch - first_epoch >= p) {
            return Ok(None);
        }
        let started = Instant::now();
        let cropped = crops.then(|| Samples::cropped(spec.data, &split.train, &normalization, opts.aug_stretch, &mut run.rng));
        let train_set = cropped.as_ref().unwrap_or(&train_set);
        let mut order: Vec<usize> = (0..train_set.len()).collect();
        run.rng.shuffle(&mut order);
        let (mut loss_sum, mut correct) = (0.0, 0usize);
        let mut lr = schedule.at(run.step);
        for rows in order.chunks(opts.batch_size) {
            let rng = &mut run.rng;
            let (x, y) = train_set.batch(rows, |s| augment(s, &normalization, opts, rng))?;
            lr = schedule.at(run.step);
            let (loss, logits) = learner.step(&x, &y, opts, lr, &mut run.rng)?;
            run.step += 1;
            if let Some(average) = &mut average {
                average.update(run.step)?;
            }
            loss_sum += loss * rows.len() as f64;
            let predicted = logits.argmax(D::Minus1)?.to_vec1::<u32>()?;
            correct += predicted.iter().zip(y.to_vec1::<u32>()?).filter(|(p, l)| **p == *l).count();
            bar.inc(1);
        }
        // With weight averaging, the average is what is evaluated, selected and checkpointed.
        if let Some(average) = &mut average {
            average.swap()?;
        }
        let val = evaluate(&learner.model, &val_set)?;
        let improved =
            run.best.as_ref().is_none_or(|b| val.accuracy > b.val_accuracy || (val.accuracy == b.val_accuracy && val.loss < b.val_loss));
        let mut test_accuracy = None;
        if improved {
            let test = if test_set.is_empty() { None } else { Some(evaluate(&learner.model, &test_set)?.accuracy) };
            test_accuracy = test;
            checkpoint::save(&run_dir.model(), &learner.varmap, &meta_for(epoch, val.accuracy, test))?;
            run.best = Some(Best { epoch, val_accuracy: val.accuracy, val_loss: val.loss, test_accuracy: test.unwrap_or(f64::NAN) });
        }
        if let Some(average) = &mut average {
            average.swap()?;
        }
        let seconds = started.elapsed().as_secs_f64();
        run.wall_seconds += seconds;
        run.epochs_done = epoch;
        let n = train_set.len() as f64;
        let line = EpochMetrics {
            epoch,
            lr,
            train_loss: loss_sum / n,
            train_accuracy: correct as f64 / n,
            val_loss: val.loss,
            val_accuracy: val.accuracy,
            test_accuracy,
            seconds,
        };
        checkpoint::replace_dir(&last, |dir| {
            checkpoint::write_files(dir, &learner.varmap, &meta_for(epoch, val.accuracy, None))?;
            let files = Checkpoint(dir);
            learner.optimizer.save(&files.optimizer())?;
            if let Some(average) = &average {
                average.save(&files.average())?;
            }
            write_json(&files.state(), &run)
        })?;
        writeln!(log, "{}", serde_json::to_string(&line).expect("plain data")).map_err(Error::io(out))?;
        crate::plot::curves::write_run(out)?;
        let best = run.best.as_ref().expect("set after the first epoch");
        bar.set_message(format!(
            "epoch {epoch}/{} loss {:.3} train {:.3} val {:.3} (best {:.3} @ {})",
            opts.epochs, line.train_loss, line.train_accuracy, val.accuracy, best.val_accuracy, best.epoch
        ));
    }
    let best = run.best.clone().ok_or_else(|| Error::Usage("no epoch was trained (epochs = 0)".into()))?;
    calibrate_stopping(&run_dir.model(), &val_set)?;
    let result = RunResult {
        val_fold: spec.val_fold,
        seed: opts.seed,
        best_epoch: best.epoch,
        val_accuracy: best.val_accuracy,
        test_accuracy: best.test_accuracy,
        epochs: opts.epochs,
        wall_seconds: run.wall_seconds,
    };
    write_json(&result_path, &result)?;
    Ok(Some(result))
}

/// Calibrates the stopping rule of provisional answers ([`crate::anytime`]) for the PVT³
/// checkpoint in `dir` on the validation samples, into its provenance (which the exporter
/// writes into the file). Other networks, and PVT³ with a spectral head, give no provisional answers.
fn calibrate_stopping(dir: &Path, val_set: &Samples) -> Result<()> {
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

#[cfg(test)]
pub(crate) mod tests;
