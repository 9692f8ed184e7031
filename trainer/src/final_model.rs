//! The model a user ships: trained on every labelled touch with what a cross-validation of the
//! same options chose, the median of the epochs its runs selected by validation, its pruning and
//! fine-tuning, its stopping rule. No touch is left to validate or test it, so the
//! cross-validation is its measurement: its provenance (and the exported file's) states the
//! accuracy the cross-validation measured, with its interval ([`Expected`]).

use std::path::{Path, PathBuf};

use indicatif::ProgressBar;
use pvt3_models::weights::varmap_tensors;
use pvt3_spec::names;
use pvt3_spec::prune::PatchChoice;

use crate::checkpoint::{self, Meta};
use crate::cv::CvSummary;
use crate::data::Dataset;
use crate::json::{read_json, write_json_atomically};
use crate::options::TrainOptions;
use crate::provenance::{Expected, Stopping};
use crate::prune::{prune_and_fine_tune, PruneStage};
use crate::run_dir::{Checkpoint, CrossValidation, Run, CV_SUMMARY};
use crate::spectrum_fit::{form::Form, Choice};
use crate::train::{train, RunResult, RunSpec};
use crate::{Error, Result};

/// A final model as a cross-validation chose it.
#[derive(Clone, Debug)]
pub struct Plan {
    /// The first run's trained checkpoint: configuration, options, classes, data set.
    pub meta: Meta,
    /// Epochs of training (the median the runs selected) and the expected accuracy.
    pub epochs: usize,
    pub expected: Expected,
    /// The stopping rule the cross-validation wrote into its runs.
    pub stopping: Option<Stopping>,
    /// The form of camera head the runs chose most often on their validation folds
    /// ([`camera_head`]); `None` without a camera head.
    pub camera_head: Option<Choice>,
    /// With pruning: the stage, its fine-tuning the median the pruned runs selected, and theirs.
    pub pruned: Option<(PruneStage, Expected, Option<Stopping>)>,
}

/// Why a cross-validation whose runs learnt from other runs (`--distill`) or another sensor
/// (`--joint`) has no final model, and what to ship instead (`run`: one of its runs).
fn learnt_from_others(options: &TrainOptions, partner: bool, run: &Path) -> Option<String> {
    let instead = format!("Ship one of its runs (pvt3 export {})", run.display());
    if let Some(teachers) = &options.distillation.teachers {
        return Some(format!(
            "its runs learnt from the runs of {teachers} (--distill) on their own splits, and a final model has no split: its \
             teachers would have to be final models first, which pvt3 final does not train. {instead}, or the teachers' \
             final model (pvt3 final {teachers})"
        ));
    }
    (options.joint.is_some() || partner).then(|| {
        format!(
            "its runs trained with another sensor's touches of their own split (--joint), and a final model has no split. \
             {instead}, or a final model of a cross-validation of this sensor alone"
        )
    })
}

impl Plan {
    /// Reads the cross-validation in `cv` (its `cv.json` and first run), refusing one with runs
    /// still training, or whose runs learnt from other runs (`--distill`) or sensors (`--joint`):
    /// each run learnt from teachers or a partner trained on its own split, and a final model,
    /// which has no split, would need final models of them first, which `pvt3 final` does not
    /// train. The refusal names what to ship instead.
    pub fn read(cv: &Path) -> Result<Self> {
        let summary: CvSummary = read_json(&cv.join(CV_SUMMARY))?;
        let refuse = |why: String| Error::Usage(format!("a final model of {}: {why}", cv.display()));
        if !summary.unfinished.is_empty() {
            return Err(refuse(format!("{} runs are still training ({})", summary.unfinished.len(), summary.unfinished.join(", "))));
        }
        let first = summary.runs.first().ok_or_else(|| refuse("it has no finished run".into()))?;
        let fold = first.val_fold.ok_or_else(|| refuse("its runs are final models themselves".into()))?;
        let run = CrossValidation(cv).run(first.seed, fold);
        let (_, meta) = checkpoint::load_meta(&Run(&run).model())?;
        let options = &meta.provenance.options;
        if let Some(why) = learnt_from_others(options, summary.partner.is_some(), &run) {
            return Err(refuse(why));
        }
        let expected = |pruned: bool| {
            let (runs, mean, std, ci95) = match pruned {
                false => (&summary.runs, Some(summary.mean_test_accuracy), Some(summary.std_test_accuracy), summary.ci95_test_accuracy),
                true => (
                    &summary.pruned_runs,
                    summary.pruned_mean_test_accuracy,
                    summary.pruned_std_test_accuracy,
                    summary.pruned_ci95_test_accuracy,
                ),
            };
            Expected {
                cv: cv.display().to_string(),
                seeds: summary.seeds.clone(),
                runs: runs.len(),
                pruned,
                mean_test_accuracy: mean.unwrap_or(f64::NAN),
                std_test_accuracy: std.unwrap_or(f64::NAN),
                ci95_test_accuracy: ci95,
                no_interval: ci95.is_none().then(|| crate::cv::NO_INTERVAL.to_string()),
                selected_epochs: runs.iter().map(|r| r.best_epoch).collect(),
            }
        };
        let dense = expected(false);
        let pruned = match &summary.pruning {
            Some(stage) => {
                let pruned = expected(true);
                let (_, pruned_meta) = checkpoint::load_meta(&Run(&Run(&run).pruned()).model())?;
                let mut stage = PruneStage { epochs: median(&pruned.selected_epochs), ..stage.clone() };
                if stage.spec.patches > 0.0 && stage.spec.patch_choice == PatchChoice::Validation {
                    stage.kept_patches = Some(most_kept_patches(cv, &summary.pruned_runs)?);
                }
                Some((stage, pruned, pruned_meta.provenance.stopping))
            }
            None => None,
        };
        let camera_head = camera_head(cv, &summary.runs)?;
        let epochs = median(&dense.selected_epochs);
        Ok(Self { epochs, camera_head, stopping: meta.provenance.stopping.clone(), expected: dense, meta, pruned })
    }

    /// The data set the cross-validation trained on (`data`, by default its own), every touch
    /// of it: refused when its touches are not the cross-validation's.
    pub fn dataset(&self, data: Option<&Path>) -> Result<Dataset> {
        let p = &self.meta.provenance;
        let own = PathBuf::from(&p.data);
        let path = data.unwrap_or(&own);
        let data = Dataset::load(path, p.seed)?;
        if let Some(recorded) = &p.trained_on {
            if data.digest() != recorded.digest {
                return Err(Error::Usage(format!(
                    "{} holds other touches than the cross-validation {} trained on (digest {}, recorded {})",
                    path.display(),
                    self.expected.cv,
                    data.digest(),
                    recorded.digest
                )));
            }
        }
        // The cross-validation answered test touches shorter than its window from the tokens they
        // fill; a final model trains on each touch, and a window needs the whole of one.
        let frames = self.meta.config.frames;
        let short: Vec<usize> = (0..data.len()).filter(|&i| data.lengths[i] < frames).collect();
        if let Some(&first) = short.first() {
            return Err(Error::Usage(format!(
                "{} touches are shorter than the cross-validation's window of {frames} frames (the first: {}), and a final model trains on whole windows: leave them out, or cross-validate a shorter window (--set frames=N)",
                short.len(),
                data.touch_name(first)
            )));
        }
        Ok(data)
    }

    /// Trains the final model into the run directory `out` (and with pruning, prunes and
    /// fine-tunes it into `out/pruned`), writes the cross-validation's stopping rule and
    /// expected accuracy into it, and returns the checkpoint to ship.
    pub fn train(&self, data: &Dataset, out: &Path, resume: bool, bar: &ProgressBar) -> Result<PathBuf> {
        let meta = &self.meta;
        let spec = RunSpec {
            data,
            config: meta.config.clone(),
            val_fold: None,
            options: crate::options::TrainOptions {
                optimization: crate::options::Optimization { epochs: self.epochs, ..meta.provenance.options.optimization.clone() },
                camera_head: self.camera_head,
                ..meta.provenance.options.clone()
            },
            classes: meta.classes.clone(),
            pause_after: None,
            start: None,
            pruning: None,
            partner: None,
        };
        train(&spec, out, resume, bar)?;
        let dense = Run(out).model();
        stamp(&dense, &self.stopping, &self.expected)?;
        let Some((stage, expected, stopping)) = &self.pruned else { return Ok(dense) };
        let pruned = Run(out).pruned();
        prune_and_fine_tune(&dense, data, stage, &pruned, resume, bar)?;
        stamp(&Run(&pruned).model(), stopping, expected)?;
        Ok(Run(&pruned).model())
    }
}

/// The camera head a final model takes, which has no validation fold to choose by: what the
/// cross-validation's runs chose (`crate::spectrum_fit::recorded`), as [`most_chosen`] reads
/// them. `None` where no run has a camera head.
fn camera_head(cv: &Path, runs: &[RunResult]) -> Result<Option<Choice>> {
    let mut chosen = Vec::new();
    for r in runs {
        let fold = r.val_fold.expect("a cross-validation's run validates");
        chosen.extend(crate::spectrum_fit::recorded(&CrossValidation(cv).run(r.seed, fold))?.map(|c| c.choice));
    }
    Ok(most_chosen(&chosen))
}

/// The form most of `chosen` took (ties to the earlier of [`Form::ALL`]), with the median
/// strength and scale of those that took it (the upper of two middle ones, as [`median`]).
fn most_chosen(chosen: &[Choice]) -> Option<Choice> {
    let count = |form: Form| chosen.iter().filter(|c| c.form == form).count();
    let form = Form::ALL.into_iter().rev().max_by_key(|f| count(*f)).filter(|f| count(*f) > 0)?;
    let of =
        |value: fn(&Choice) -> Option<f64>| middle(chosen.iter().filter(|c| c.form == form).filter_map(value).collect(), f64::total_cmp);
    Some(Choice { form, strength: of(|c| c.strength), scale: of(|c| c.scale) })
}

/// The patches a final model keeps where its cross-validation chose them by validation, which a
/// final model has none of: those the cross-validation's pruned runs kept most often (ties to the
/// lower patch), as many as each kept.
fn most_kept_patches(cv: &Path, runs: &[RunResult]) -> Result<Vec<bool>> {
    let mut masks = Vec::new();
    for r in runs {
        let fold = r.val_fold.ok_or_else(|| Error::Usage(format!("{}: a pruned run without a validation fold", cv.display())))?;
        let (_, _, varmap) = checkpoint::load(&Run(&Run(&CrossValidation(cv).run(r.seed, fold)).pruned()).model())?;
        masks.push(varmap_tensors(&varmap)?.remove(names::PATCH_MASK).map(|(_, v)| v).unwrap_or_default());
    }
    Ok(most_kept(&masks))
}

/// Of patch masks that each keep (are not zero on) as many patches, the patches kept most often,
/// as many; ties to the lower patch.
fn most_kept(masks: &[Vec<f32>]) -> Vec<bool> {
    let n = masks.first().map_or(0, Vec::len);
    let votes: Vec<usize> = (0..n).map(|p| masks.iter().filter(|m| m[p] != 0.0).count()).collect();
    let kept = masks.first().map_or(0, |m| m.iter().filter(|v| **v != 0.0).count());
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|a, b| votes[*b].cmp(&votes[*a]).then(a.cmp(b)));
    let mut keep = vec![false; n];
    order.into_iter().take(kept).for_each(|p| keep[p] = true);
    keep
}

/// The median of `epochs`, the upper of the middle two of an even count.
fn median(epochs: &[usize]) -> usize {
    middle(epochs.to_vec(), Ord::cmp).unwrap_or(0)
}

/// The middle of `values` in `order` (the upper of two middle ones); `None` without any.
fn middle<T: Copy>(mut values: Vec<T>, order: impl FnMut(&T, &T) -> std::cmp::Ordering) -> Option<T> {
    values.sort_by(order);
    values.get(values.len() / 2).copied()
}

/// Writes the stopping rule and the expected accuracy into the checkpoint `dir`'s provenance.
fn stamp(dir: &Path, stopping: &Option<Stopping>, expected: &Expected) -> Result<()> {
    let (checkpoint_dir, mut meta) = checkpoint::load_meta(dir)?;
    meta.provenance.stopping = stopping.clone();
    meta.provenance.expected = Some(expected.clone());
    write_json_atomically(&Checkpoint(&checkpoint_dir).provenance(), &meta.provenance)
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_final_model_keeps_the_patches_its_runs_kept_most_often() {
        let masks = [vec![1.1, 0.0, 0.9, 0.0], vec![1.0, 0.0, 0.0, 1.2], vec![0.0, 1.0, 1.0, 0.0]];
        assert_eq!(super::most_kept(&masks), vec![true, false, true, false], "votes 2, 1, 2, 1");
        let tied = [vec![1.0, 0.0, 0.0], vec![0.0, 0.0, 1.0]];
        assert_eq!(super::most_kept(&tied), vec![true, false, false], "a tie to the lower patch");
    }

    /// The form most runs chose, the median strength and scale among them; none without a head.
    #[test]
    fn a_final_model_takes_the_camera_head_most_runs_chose() {
        use crate::spectrum_fit::{form::Form, Choice};
        let pick = |form, strength: f64, scale: f64| Choice { form, strength: Some(strength), scale: Some(scale) };
        let runs = [
            pick(Form::Both, 0.1, 4.0),
            Choice::TEXTURE,
            pick(Form::Both, 1.0, 1.0),
            pick(Form::Pixels, 1.0, 8.0),
            pick(Form::Both, 0.01, 2.0),
        ];
        assert_eq!(super::most_chosen(&runs), Some(pick(Form::Both, 0.1, 2.0)));
        assert_eq!(super::most_chosen(&[Choice::TEXTURE, pick(Form::Pixels, 1.0, 8.0)]), Some(Choice::TEXTURE), "a tie to the texture");
        assert_eq!(super::most_chosen(&[]), None);
    }

    #[test]
    fn the_median_takes_the_upper_middle() {
        assert_eq!(super::median(&[30, 10, 20]), 20);
        assert_eq!(super::median(&[40, 10, 30, 20]), 30);
        assert_eq!(super::median(&[]), 0);
    }
}
