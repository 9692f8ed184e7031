//! One epoch's optimiser steps over a run's sensors: the run's own sensor's training windows
//! shuffled and batched; in a joint run each batch paired, touch by touch, with windows of the
//! same classes from the other sensor's ([`crate::joint::draw_partners`]); every window
//! augmented as it is batched; the sensors' learners stepped together
//! ([`super::learner::step_together`]).

use indicatif::ProgressBar;

use super::learner::{step_together, Stepped};
use super::sensor::{rows_by_class, Sensor, Tally, Validated};
use super::state::RunState;
use crate::data::augment::augment;
use crate::data::windows::Samples;
use crate::metrics::EpochMetrics;
use crate::options::TrainOptions;
use crate::schedule::Schedule;
use crate::Result;

/// What an epoch's steps measured, a tally per sensor.
pub(super) struct Trained {
    pub(super) tallies: Vec<Tally>,
    /// The learning rate of the epoch's last step.
    pub(super) lr: f64,
    /// The run's own sensor's training windows this epoch: every sensor's batches had as many.
    pub(super) windows: f64,
}

impl Trained {
    /// A sensor's line of `metrics.jsonl` for this epoch, its validation `val` beside.
    pub(super) fn line(&self, epoch: usize, seconds: f64, tally: &Tally, val: &Validated) -> EpochMetrics {
        EpochMetrics {
            epoch,
            lr: self.lr,
            train_loss: tally.loss / self.windows,
            train_accuracy: tally.correct as f64 / self.windows,
            val_loss: val.loss,
            val_accuracy: val.accuracy,
            test_accuracy: val.test_accuracy,
            seconds,
            encodings_apart: tally.apart.map(|a| a / self.windows),
        }
    }
}

/// Epoch `epoch`'s steps: every draw from `run.rng`, and `run.step` and the weight averages
/// advanced with each step.
pub(super) fn train(
    sensors: &mut [Sensor],
    epoch: usize,
    schedule: &Schedule,
    opts: &TrainOptions,
    run: &mut RunState,
    bar: &ProgressBar,
) -> Result<Trained> {
    // Windows drawn anew this epoch, each sensor's in turn (see `Sensor::crops`).
    let drawn: Vec<Option<Samples>> = (sensors.iter())
        .map(|s| s.crops.then(|| Samples::cropped(s.data, &s.split.train, &s.normalization, s.options.augmentation.stretch, &mut run.rng)))
        .collect();
    let (mut sets, mut nets) = (Vec::new(), Vec::new());
    for (sensor, drawn) in sensors.iter_mut().zip(&drawn) {
        let Sensor { net, train_set, normalization, config, .. } = sensor;
        sets.push((drawn.as_ref().unwrap_or(train_set), &*normalization, config.classes));
        nets.push(net);
    }
    // The other sensors' rows of each class: where a touch's partner is drawn.
    let same_class: Vec<Vec<Vec<usize>>> = sets[1..].iter().map(|&(set, _, classes)| rows_by_class(set, classes)).collect();
    let own = sets[0].0;
    let mut order: Vec<usize> = (0..own.len()).collect();
    run.rng.shuffle(&mut order);
    let pull = opts.joint.as_ref().map_or(0.0, |j| if epoch > j.after_epochs { j.weight } else { 0.0 });
    let mut tallies: Vec<Tally> = sets.iter().map(|_| Tally::default()).collect();
    let mut lr = schedule.at(run.step);
    for rows in order.chunks(opts.optimization.batch_size) {
        lr = schedule.at(run.step);
        let mut batches = Vec::with_capacity(sets.len());
        for (i, &(set, normalization, _)) in sets.iter().enumerate() {
            let rows = match i {
                0 => rows.to_vec(),
                _ => crate::joint::draw_partners(rows.iter().map(|&r| own.labels[r]), &same_class[i - 1], &mut run.rng)?,
            };
            let rng = &mut run.rng;
            let transform = |s: &mut [f32]| augment(s, normalization, set.grid(), &opts.augmentation, rng);
            batches.push(match nets[i].learner.cuts(opts) {
                Some(cfg) => set.cut_batch(&rows, cfg, transform)?,
                None => set.batch(&rows, transform)?,
            });
        }
        let mut learners: Vec<_> = nets.iter_mut().map(|n| &mut n.learner).collect();
        let Stepped { each, apart } = step_together(&mut learners, &batches, pull, opts, lr, &mut run.rng)?;
        for ((tally, (loss, logits)), (_, y)) in tallies.iter_mut().zip(each).zip(&batches) {
            tally.add(loss, &logits, y, rows.len())?;
            if let Some(apart) = apart {
                *tally.apart.get_or_insert(0.0) += apart * rows.len() as f64;
            }
        }
        run.step += 1;
        for net in nets.iter_mut() {
            net.update_average(run.step)?;
        }
        bar.inc(1);
    }
    Ok(Trained { tallies, lr, windows: own.len() as f64 })
}
