//! Where a trained model came from: the provenance a checkpoint records beside its weights
//! (options, split, how the touches were read, the stopping rule calibrated at the end, a final
//! model's expected accuracy). Plain data, below everything that trains, prunes or chooses, so
//! that what a checkpoint stores is defined with it and not by the commands that fill it in.

use std::path::{Path, PathBuf};

use pvt3_format::StopRule;
use serde::{Deserialize, Serialize};

use crate::json::nan_from_null;
use crate::options::TrainOptions;
use crate::{Error, Result};

/// Where a trained model came from.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Provenance {
    pub pvt3_version: String,
    pub data: String,
    /// The fold that chose the epoch; `None` for a final model, which every touch trained
    /// ([`crate::final_model`]).
    pub val_fold: Option<usize>,
    pub seed: u64,
    /// The selected (best-validation) epoch, 1-based; a final model's last.
    pub epoch: usize,
    /// NaN (`null`) where nothing validated.
    #[serde(deserialize_with = "nan_from_null")]
    pub val_accuracy: f64,
    pub test_accuracy: Option<f64>,
    pub options: TrainOptions,
    /// The pruning applied before fine-tuning, if any.
    #[serde(default)]
    pub pruning: Option<pvt3_spec::prune::PruneSpec>,
    /// The condition's levels held out as the test set (`--hold-out`), if any.
    #[serde(default)]
    pub held_out: Option<crate::data::HoldOut>,
    /// The split the run trained on, which every reload takes ([`Provenance::dataset`]); `None`
    /// in a run of a pvt3 from before it was recorded.
    #[serde(default)]
    pub trained_on: Option<crate::data::TrainedOn>,
    /// How the data set read its touches (`pvt3 import --per-distance`, `--per-force`): the
    /// exported file asks a robot for the same.
    #[serde(default)]
    pub reading: Option<pvt3_format::Reading>,
    /// How the data set's camera frames were read from the camera's (`pvt3 import` of videos or
    /// images): the exported file asks a robot's camera frames to be read alike.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera: Option<pvt3_format::Camera>,
    /// The stopping rule of provisional answers, calibrated on the validation fold when the
    /// run finished (PVT³ only). A rule of another form (an earlier pvt3's) reads as none: such a
    /// run exports without one, and `pvt3 eval --anytime` calibrates it afresh.
    #[serde(default, deserialize_with = "current_or_none")]
    pub stopping: Option<Stopping>,
    /// A final model's: the accuracy the cross-validation it follows measured, since no touch
    /// is left to test it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub expected: Option<Expected>,
}

impl Provenance {
    /// The data set the run trained on (`data`, by default its own), split as the run recorded
    /// it; refused when its touches are not the run's. A final model's other data is read as it
    /// is: every touch of its own trained it, so no split of it applies, and
    /// [`Provenance::check_testable_on`] refuses the touches that trained it wherever they lie.
    pub fn dataset(&self, data: Option<&Path>) -> Result<crate::data::Dataset> {
        let own = PathBuf::from(&self.data);
        match (self.val_fold, data) {
            (None, Some(other)) if *other != own => crate::data::Dataset::load(other, self.seed),
            _ => crate::data::Dataset::load_as_trained(data.unwrap_or(&own), self.seed, self.held_out.as_ref(), self.trained_on.as_ref()),
        }
    }

    /// Refuses to test a final model on touches that trained it: every one of its data set's,
    /// or any of `testing` (touches of `data`) whose own digest is among those it trained on
    /// (a subset of its data, or the same touches imported again), saying how many, and naming
    /// the accuracy its cross-validation measured instead.
    pub fn check_testable_on(&self, data: &crate::data::Dataset, testing: &[usize]) -> Result<()> {
        let (None, Some(trained)) = (self.val_fold, &self.trained_on) else { return Ok(()) };
        let expected = self.expected.as_ref().map_or(String::new(), |e| format!("; expected: {e}"));
        if trained.digest == data.digest() {
            return Err(Error::Usage(format!(
                "a final model: every touch of {} trained it, so none is left to test it (give --data with other touches){expected}",
                self.data
            )));
        }
        let seen: std::collections::HashSet<&String> = trained.touches.iter().collect();
        let found = testing.iter().filter(|&&i| seen.contains(&data.touch_digest(i))).count();
        match found {
            0 => Ok(()),
            _ => Err(Error::Usage(format!(
                "a final model: {found} of the {} touches to test in {} trained it (their digests are in its record of {}), and a touch that trained a model cannot test it: give touches it never read{expected}",
                testing.len(),
                data.path.display(),
                self.data
            ))),
        }
    }

    /// What a reload should say of a run that did not record its split: its folds are derived
    /// again as they were drawn then.
    pub fn split_note(&self) -> Option<String> {
        self.trained_on.is_none().then(|| {
            format!(
                "note: this run, by pvt3 {}, records no split: its folds are derived again (the file's, or drawn with seed {}{})",
                self.pvt3_version,
                self.seed,
                self.held_out.as_ref().map_or(String::new(), |h| format!(" around the held-out {h}"))
            )
        })
    }
}

fn current_or_none<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Option<Stopping>, D::Error> {
    let value = serde_json::Value::deserialize(d)?;
    Ok(serde_json::from_value(value).ok())
}

/// The stopping rule and what it did on the samples it was calibrated (or measured) on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Stopping {
    pub rule: StopRule,
    /// Accuracy with the whole touch.
    pub full_accuracy: f64,
    /// Accuracy when stopping by the rule.
    pub accuracy: f64,
    /// The share of the touch used before stopping, on average (1: the whole touch).
    pub mean_share: f64,
    /// Which validation answers the rule was calibrated on (the figures above are theirs).
    #[serde(default)]
    pub calibrated_on: CalibratedOn,
}

/// Where a stopping rule was calibrated.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CalibratedOn {
    /// The run's own validation fold (`pvt3 train`).
    #[default]
    ValidationFold,
    /// The validation answers of every run of a cross-validation, each run's model on its own
    /// validation fold (`pvt3 cv`).
    CrossValidation { runs: usize, samples: usize },
}

/// What a final model is expected to score: the cross-validation's test accuracy over its runs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Expected {
    /// The cross-validation's directory.
    pub cv: String,
    pub seeds: Vec<u64>,
    pub runs: usize,
    /// Of the pruned and fine-tuned runs, where the cross-validation pruned.
    pub pruned: bool,
    pub mean_test_accuracy: f64,
    pub std_test_accuracy: f64,
    /// Student's t over the seeds' means; `None` with one seed.
    pub ci95_test_accuracy: Option<[f64; 2]>,
    /// Why there is no interval, where there is none ([`crate::cv::NO_INTERVAL`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub no_interval: Option<String>,
    /// The epochs the runs selected by validation (of their fine-tuning, when pruned), whose
    /// median the final model trained.
    pub selected_epochs: Vec<usize>,
}

/// The expected accuracy in words, as `pvt3 final` and `pvt3 eval`'s refusal say it.
impl std::fmt::Display for Expected {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:.4} ± {:.4}", self.mean_test_accuracy, self.std_test_accuracy)?;
        if let Some([lo, hi]) = self.ci95_test_accuracy {
            write!(f, ", 95 % interval of the mean [{lo:.4}, {hi:.4}]")?;
        }
        let seeds = match self.seeds.len() {
            1 => " (one seed)".to_string(),
            n => format!(" ({n} seeds)"),
        };
        let pruned = if self.pruned { "pruned " } else { "" };
        write!(f, ", the test accuracy of the cross-validation {}'s {} {pruned}runs{seeds}", self.cv, self.runs)?;
        match &self.no_interval {
            Some(why) => write!(f, "; {why}"),
            None => Ok(()),
        }
    }
}

/// A provenance for the tests: a run of no data, its every record empty.
#[cfg(test)]
impl Provenance {
    pub(crate) fn example() -> Self {
        Self {
            pvt3_version: "test".into(),
            data: String::new(),
            val_fold: Some(0),
            seed: 0,
            epoch: 0,
            val_accuracy: 0.0,
            test_accuracy: None,
            options: TrainOptions::default(),
            pruning: None,
            held_out: None,
            trained_on: None,
            reading: None,
            camera: None,
            stopping: None,
            expected: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run of an earlier pvt3 (its stopping rule in another form) still loads, without a rule.
    #[test]
    fn a_stopping_rule_of_another_form_reads_as_none() {
        let p = Provenance { data: "d".into(), epoch: 1, val_accuracy: 0.5, ..Provenance::example() };
        let mut json = serde_json::to_value(&p).unwrap();
        json["stopping"] = serde_json::json!({"threshold": 0.9, "full_accuracy": 0.9, "accuracy": 0.9, "mean_share": 0.5});
        assert_eq!(serde_json::from_value::<Provenance>(json.clone()).unwrap().stopping, None);
        let rule =
            serde_json::json!({"rule": {"top_probability": 0.9, "agreeing": 3}, "full_accuracy": 0.9, "accuracy": 0.9, "mean_share": 0.5});
        json["stopping"] = rule;
        assert_eq!(serde_json::from_value::<Provenance>(json).unwrap().stopping.unwrap().rule.agreeing, 3);
    }
}
