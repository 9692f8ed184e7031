//! One sensor's network in a run (a joint run trains two): what its epochs read, its learner,
//! its validation and checkpoints, its resume state.

use std::path::{Path, PathBuf};

use candle_core::{Tensor, D};
use candle_nn::VarMap;
use indicatif::ProgressBar;
use pvt3_models::Config;
use pvt3_spec::prune::PruneSpec;
use pvt3_spec::weights::Tensors;
use serde::{Deserialize, Serialize};

use super::learner::{is_mask, Net};
use super::{Learner, RunSpec};
use crate::average::WeightAverage;
use crate::checkpoint::{self, Meta};
use crate::data::normalization::Normalization;
use crate::data::{Dataset, Split, TrainedOn};
use crate::joint::Partner;
use crate::json::nan_from_null;
use crate::optim::is_weight_matrix;
use crate::options::TrainOptions;
use crate::provenance::Provenance;
use crate::run_dir::{Checkpoint, Run};
use crate::spectrum_fit::Chosen;
use crate::{data::windows::Samples, evaluate::evaluate};
use crate::{Error, Result};

/// One sensor's network in a run and what its epochs read: its split as windows, normalised,
/// its learner and weight average. A joint run (`--joint`) trains two side by side.
pub(super) struct Sensor<'a> {
    pub(super) data: &'a Dataset,
    /// Its options: a joint run's other sensor records the run's data set as its partner.
    pub(super) options: TrainOptions,
    /// Its run directory: the run's, or a joint run's `partner/` in it.
    pub(super) dir: PathBuf,
    pub(super) config: Config,
    pub(super) classes: Vec<String>,
    pub(super) normalization: Normalization,
    pub(super) split: Split,
    /// The split as its checkpoints record it (a final model's with each touch's digest), read
    /// once: it holds for the whole run.
    trained_on: TrainedOn,
    /// Every training touch read as its evaluation windows: what fits the spectral head's
    /// standardisation, and each epoch's batches when every touch is one window long.
    pub(super) train_set: Samples<'a>,
    /// A touch longer than a window (or stretched) gives each epoch one window drawn at random.
    pub(super) crops: bool,
    pub(super) val_set: Samples<'a>,
    pub(super) test_set: Samples<'a>,
    pub(super) net: Net,
}

impl<'a> Sensor<'a> {
    /// Its network starts from `start`'s weights, or seeded; with `share`, its temporal
    /// transformer is that learner's ([`Learner::sharing`]).
    pub(super) fn new(
        data: &'a Dataset,
        config: Config,
        classes: Vec<String>,
        (val_fold, opts): (Option<usize>, &TrainOptions),
        dir: &Path,
        (start, share): (Option<&Tensors>, Option<&VarMap>),
    ) -> Result<Self> {
        data.check_fits(&config)?;
        let split: Split = data.split_for(val_fold)?;
        let normalization = crate::data::normalization::fit(data, &split.train, config.frames);
        let train_set = Samples::new(data, &split.train, &normalization);
        let crops = opts.augmentation.stretch > 0.0 || split.train.iter().any(|&i| data.lengths[i] > config.frames);
        let val_set = Samples::new(data, &split.val, &normalization);
        let test_set = Samples::new(data, &split.test, &normalization);
        let learner = match share {
            Some(shared) => Learner::sharing(&config, opts, shared, &format!("{}.", pvt3_spec::names::TEMPORAL))?,
            None => Learner::new(&config, opts, start)?,
        };
        // With weight averaging, the average of the weights as they start.
        let average = if opts.ema > 0.0 { Some(WeightAverage::new(&learner.varmap, opts.ema)?) } else { None };
        let (options, dir) = (opts.clone(), dir.to_path_buf());
        let trained_on = data.trained_on(val_fold.is_none());
        Ok(Self {
            trained_on,
            data,
            options,
            dir,
            net: Net { learner, average },
            config,
            classes,
            normalization,
            split,
            train_set,
            crops,
            val_set,
            test_set,
        })
    }

    /// Readies the network for the epochs of this call: its spectral heads fitted to its
    /// training windows (`fit_heads`: a fresh run's), then the zeros fine-tuning holds. Returns
    /// what a camera head's fit chose, which it records in the run directory.
    pub(super) fn ready(&mut self, fit_heads: bool, opts: &TrainOptions) -> Result<Option<Chosen>> {
        let learner = &mut self.net.learner;
        let mut chosen = None;
        if fit_heads {
            chosen = crate::spectrum_fit::fit(&learner.model, &learner.varmap, &self.train_set, &self.val_set, opts.camera_head)?;
            if let Some(chosen) = &chosen {
                crate::spectrum_fit::record(&self.dir, chosen)?;
            }
        }
        if opts.held.pruned {
            learner.hold_zeros(is_mask)?;
        }
        if opts.held.zero_weights {
            learner.hold_zeros(is_weight_matrix)?;
        }
        Ok(chosen)
    }

    pub(super) fn meta(&self, val_fold: Option<usize>, pruning: &Option<PruneSpec>, epoch: usize, val: f64, test: Option<f64>) -> Meta {
        Meta {
            config: self.config.clone(),
            normalization: self.normalization.clone(),
            classes: self.classes.clone(),
            provenance: Provenance {
                pvt3_version: env!("CARGO_PKG_VERSION").to_string(),
                data: self.data.path.display().to_string(),
                val_fold,
                seed: self.options.seed,
                epoch,
                val_accuracy: val,
                test_accuracy: test,
                options: self.options.clone(),
                pruning: pruning.clone(),
                held_out: self.data.held_out.clone(),
                trained_on: Some(self.trained_on.clone()),
                reading: self.data.reading,
                camera: self.data.camera,
                stopping: None,
                expected: None,
            },
        }
    }

    /// The end of an epoch: the network (its weight average, when averaging) evaluated on
    /// validation; when it improved on `best`, on the test touches too and checkpointed into
    /// its run's `model/`. With nothing to validate (a final model) every epoch is checkpointed, so the
    /// last is kept.
    pub(super) fn validate(
        &mut self,
        epoch: usize,
        best: &mut Option<Best>,
        (val_fold, pruning): (Option<usize>, &Option<PruneSpec>),
    ) -> Result<Validated> {
        if let Some(average) = &mut self.net.average {
            average.swap()?;
        }
        let val = match self.val_set.is_empty() {
            true => crate::evaluate::Evaluation { loss: f64::NAN, accuracy: f64::NAN, predictions: Vec::new(), labels: Vec::new() },
            false => evaluate(&self.net.learner.model, &self.val_set)?,
        };
        let improved = self.val_set.is_empty()
            || best.as_ref().is_none_or(|b| val.accuracy > b.val_accuracy || (val.accuracy == b.val_accuracy && val.loss < b.val_loss));
        let mut test_accuracy = None;
        if improved {
            let test = if self.test_set.is_empty() { None } else { Some(evaluate(&self.net.learner.model, &self.test_set)?.accuracy) };
            test_accuracy = test;
            checkpoint::save(&Run(&self.dir).model(), &self.net.learner.varmap, &self.meta(val_fold, pruning, epoch, val.accuracy, test))?;
            *best = Some(Best { epoch, val_accuracy: val.accuracy, val_loss: val.loss, test_accuracy: test.unwrap_or(f64::NAN) });
        }
        if let Some(average) = &mut self.net.average {
            average.swap()?;
        }
        Ok(Validated { loss: val.loss, accuracy: val.accuracy, test_accuracy })
    }
}

/// The run's sensors, each with its options and run directory (made here): the run's own, its
/// teachers loaded (`--distill`), and a joint run's other sensor; each readied for the epochs of
/// this call: restored from the run's `last/` and its step when it resumes (`resumed`), otherwise
/// its spectral heads fitted ([`Sensor::ready`]: what a camera head's fit chose is said on `bar`).
pub(super) fn of_run<'a>(
    spec: &RunSpec<'a>,
    config: Config,
    opts: &TrainOptions,
    out: &Path,
    resumed: Option<(&Path, usize)>,
    bar: &ProgressBar,
) -> Result<Vec<Sensor<'a>>> {
    let mut main = Sensor::new(spec.data, config, spec.classes.clone(), (spec.val_fold, opts), out, (spec.start.as_ref(), None))?;
    let mut sensors = Vec::new();
    if let Some(p) = &spec.partner {
        p.check(main.data, &main.config, &main.classes, opts)?;
        let share = opts.joint.as_ref().is_some_and(|j| j.share_temporal).then_some(&main.net.learner.varmap);
        let options = Partner::options(opts, spec.data);
        let dir = Run(out).partner();
        sensors.push(Sensor::new(p.data, p.config.clone(), p.classes.clone(), (spec.val_fold, &options), &dir, (None, share))?);
    }
    if let Some(teachers) = &opts.distillation.teachers {
        let trained_on = (spec.val_fold, &main.data.trained_on(false));
        let teachers = crate::distill::Teachers::load(Path::new(teachers), trained_on, &main.normalization, &main.classes, out)?;
        main.net.learner.teachers = Some(teachers);
    }
    sensors.insert(0, main);
    for sensor in &sensors {
        std::fs::create_dir_all(&sensor.dir).map_err(Error::io(&sensor.dir))?;
    }
    // A run from given weights (fine-tuning) keeps its spectral heads as they are, unless it
    // prunes patches a head over the image's space read: it now reads them as 0.
    let prunes_pixels = spec.config.spectral_space() && spec.pruning.as_ref().is_some_and(|p| p.patches > 0.0);
    let fit_heads = resumed.is_none() && (spec.start.is_none() || prunes_pixels);
    for (i, sensor) in sensors.iter_mut().enumerate() {
        if let Some((last, step)) = resumed {
            sensor.net.restore(&Checkpoint(last).of_sensor(i), step)?;
        }
        if let Some(chosen) = sensor.ready(fit_heads, opts)? {
            bar.println(format!("{}: {chosen}", sensor.dir.display()));
        }
    }
    Ok(sensors)
}

/// A sensor's best epoch so far, by validation.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Best {
    pub(super) epoch: usize,
    #[serde(deserialize_with = "nan_from_null")]
    pub(super) val_accuracy: f64,
    #[serde(deserialize_with = "nan_from_null")]
    pub(super) val_loss: f64,
    #[serde(deserialize_with = "nan_from_null")]
    pub(super) test_accuracy: f64,
}

/// A sensor's validation at the end of an epoch.
pub(super) struct Validated {
    pub(super) loss: f64,
    pub(super) accuracy: f64,
    pub(super) test_accuracy: Option<f64>,
}

/// Losses and correct answers of one sensor's batches over an epoch, and in a joint run the
/// encodings' distance to the other sensor's.
#[derive(Default)]
pub(super) struct Tally {
    pub(super) loss: f64,
    pub(super) correct: usize,
    pub(super) apart: Option<f64>,
}

impl Tally {
    pub(super) fn add(&mut self, loss: f64, logits: &Tensor, y: &Tensor, rows: usize) -> Result<()> {
        self.loss += loss * rows as f64;
        let predicted = logits.argmax(D::Minus1)?.to_vec1::<u32>()?;
        self.correct += predicted.iter().zip(y.to_vec1::<u32>()?).filter(|(p, l)| **p == *l).count();
        Ok(())
    }
}

/// Each class's rows in `set`: where a joint run draws the partner of a touch of that class.
pub(super) fn rows_by_class(set: &Samples, classes: usize) -> Vec<Vec<usize>> {
    let mut rows = vec![Vec::new(); classes];
    for (r, &label) in set.labels.iter().enumerate() {
        rows[label as usize].push(r);
    }
    rows
}
