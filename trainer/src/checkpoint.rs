//! Checkpoints are directories of files named in [`crate::run_dir::Checkpoint`]: configuration,
//! weights, normalisation, class names and provenance (and in a run's `last/`, what resuming
//! needs besides). A directory is written under a temporary name and swapped
//! in by renames, so a crash never leaves a half-written checkpoint; if it strikes between the two
//! renames, the previous version is still found under `NAME.old`.

use std::path::{Path, PathBuf};

use candle_nn::VarMap;
use pvt3_models::weights::{load_weights, save_weights};
use pvt3_models::{Config, Model};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::data::normalization::Normalization;
use crate::options::TrainOptions;
use crate::run_dir::{Checkpoint, Run};
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
    pub stopping: Option<crate::anytime::Stopping>,
    /// A final model's: the accuracy the cross-validation it follows measured, since no touch
    /// is left to test it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub expected: Option<crate::final_model::Expected>,
}

impl Provenance {
    /// The data set the run trained on (`data`, by default its own), split as the run recorded
    /// it; refused when its touches are not the run's.
    pub fn dataset(&self, data: Option<&Path>) -> Result<crate::data::Dataset> {
        let own = PathBuf::from(&self.data);
        crate::data::Dataset::load_as_trained(data.unwrap_or(&own), self.seed, self.held_out.as_ref(), self.trained_on.as_ref())
    }

    /// Refuses to test a final model on the touches that trained it (every one of its data
    /// set's), naming the accuracy its cross-validation measured instead.
    pub fn check_testable_on(&self, data: &crate::data::Dataset) -> Result<()> {
        let own = self.trained_on.as_ref().is_some_and(|t| t.digest == data.digest());
        match (self.val_fold, own) {
            (None, true) => Err(Error::Usage(format!(
                "a final model: every touch of {} trained it, so none is left to test it (give --data with other touches){}",
                self.data,
                self.expected.as_ref().map_or(String::new(), |e| format!("; expected: {e}"))
            ))),
            _ => Ok(()),
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

/// Reads a number, or `null` as NaN: how JSON writes a figure that was not measured (a final
/// model's validation accuracy, a run's test accuracy without test touches).
pub fn nan_from_null<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

fn current_or_none<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Option<crate::anytime::Stopping>, D::Error> {
    let value = serde_json::Value::deserialize(d)?;
    Ok(serde_json::from_value(value).ok())
}

/// A baked model with everything the exporter needs: what `pvt3 bake` writes.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct BakedFile {
    pub baked: pvt3_spec::baked::BakedPvt3,
    pub normalization: Normalization,
    pub classes: Vec<String>,
    pub provenance: Provenance,
}

impl BakedFile {
    /// Bakes the checkpoint at `path` (a run or checkpoint directory).
    pub fn from_checkpoint(path: &Path) -> Result<Self> {
        let (meta, _, varmap) = load(path)?;
        let baked = pvt3_spec::bake::bake(&meta.config, &pvt3_models::weights::varmap_tensors(&varmap)?)?;
        Ok(Self { baked, normalization: meta.normalization, classes: meta.classes, provenance: meta.provenance })
    }

    /// A checkpoint directory (baked on the way) or a file written by `pvt3 bake`.
    pub fn load(path: &Path) -> Result<Self> {
        if path.is_dir() {
            return Self::from_checkpoint(path);
        }
        let bytes = std::fs::read(path).map_err(Error::io(path))?;
        serde_json::from_slice(&bytes)
            .map_err(|e| checkpoint_error(path, format!("neither a checkpoint directory nor a baked model from `pvt3 bake` ({e})")))
    }

    /// The ONNX metadata: class names and where the model came from.
    pub fn metadata(&self) -> pvt3_export::Metadata {
        pvt3_export::Metadata {
            classes: self.classes.clone(),
            provenance: serde_json::to_value(&self.provenance).expect("plain data serialises"),
            stop_rule: self.provenance.stopping.as_ref().map(|s| s.rule),
            reading: self.provenance.reading,
            camera: self.provenance.camera,
        }
    }
}

/// Everything in a checkpoint except the weights.
#[derive(Clone, Debug)]
pub struct Meta {
    pub config: Config,
    pub normalization: Normalization,
    pub classes: Vec<String>,
    pub provenance: Provenance,
}

fn checkpoint_error(path: &Path, reason: impl Into<String>) -> Error {
    Error::Checkpoint { path: path.to_path_buf(), reason: reason.into() }
}

pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    let text = serde_json::to_string_pretty(value).expect("plain data serialises");
    std::fs::write(path, text + "\n").map_err(Error::io(path))
}

/// Writes JSON to a temporary file and renames it over `path`. The temporary file is this
/// process's own, so that jobs writing the same file at once (`cv --only` in a job array) each
/// rename a whole one.
pub fn write_json_atomically<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    let tmp = sibling(path, &format!(".{}.tmp", std::process::id()));
    write_json(&tmp, value)?;
    std::fs::rename(&tmp, path).map_err(Error::io(path))
}

pub fn read_json<T: DeserializeOwned>(path: &Path) -> Result<T> {
    let text = std::fs::read_to_string(path).map_err(Error::io(path))?;
    serde_json::from_str(&text).map_err(|e| checkpoint_error(path, format!("malformed JSON ({e})")))
}

fn sibling(target: &Path, suffix: &str) -> PathBuf {
    let mut name = target.file_name().expect("a directory name").to_os_string();
    name.push(suffix);
    target.with_file_name(name)
}

/// Writes a directory through `fill` under a temporary name, then swaps it in for `target`.
pub fn replace_dir(target: &Path, fill: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let tmp = sibling(target, ".tmp");
    let old = sibling(target, ".old");
    if tmp.exists() {
        std::fs::remove_dir_all(&tmp).map_err(Error::io(&tmp))?;
    }
    std::fs::create_dir_all(&tmp).map_err(Error::io(&tmp))?;
    fill(&tmp)?;
    if target.exists() {
        if old.exists() {
            std::fs::remove_dir_all(&old).map_err(Error::io(&old))?;
        }
        std::fs::rename(target, &old).map_err(Error::io(target))?;
    }
    std::fs::rename(&tmp, target).map_err(Error::io(&tmp))?;
    if old.exists() {
        std::fs::remove_dir_all(&old).map_err(Error::io(&old))?;
    }
    Ok(())
}

/// The directory to read for `target`: itself, or the `.old` copy a crash left behind.
pub fn existing_dir(target: &Path) -> Option<PathBuf> {
    let old = sibling(target, ".old");
    if target.is_dir() {
        Some(target.to_path_buf())
    } else if old.is_dir() {
        Some(old)
    } else {
        None
    }
}

/// Writes the checkpoint files into an existing directory.
pub fn write_files(dir: &Path, varmap: &VarMap, meta: &Meta) -> Result<()> {
    let files = Checkpoint(dir);
    write_json(&files.config(), &meta.config)?;
    write_json(&files.normalization(), &meta.normalization)?;
    write_json(&files.classes(), &meta.classes)?;
    write_json(&files.provenance(), &meta.provenance)?;
    save_weights(varmap, &files.weights())?;
    Ok(())
}

/// Writes a whole checkpoint directory atomically.
pub fn save(dir: &Path, varmap: &VarMap, meta: &Meta) -> Result<()> {
    replace_dir(dir, |tmp| write_files(tmp, varmap, meta))
}

/// Reads the metadata of a checkpoint directory (a run directory is read through its `model/`).
pub fn load_meta(path: &Path) -> Result<(PathBuf, Meta)> {
    let dir = resolve(path)?;
    let files = Checkpoint(&dir);
    let config: Config = read_json(&files.config())?;
    config.validate().map_err(|e| checkpoint_error(&dir, e.to_string()))?;
    let normalization: Normalization = read_json(&files.normalization())?;
    let classes: Vec<String> = read_json(&files.classes())?;
    let provenance: Provenance = read_json(&files.provenance())?;
    if !normalization.fits(&config) {
        return Err(checkpoint_error(
            &dir,
            format!("normalization.json does not fit the configuration ({} channels × {} frames)", config.sensor_channels(), config.frames),
        ));
    }
    if classes.len() != config.classes {
        return Err(checkpoint_error(
            &dir,
            format!("classes.json names {} classes, the configuration has {}", classes.len(), config.classes),
        ));
    }
    Ok((dir, Meta { config, normalization, classes, provenance }))
}

/// Loads a checkpoint: its metadata and the model with its weights.
pub fn load(path: &Path) -> Result<(Meta, Model, VarMap)> {
    let (dir, meta) = load_meta(path)?;
    let (model, varmap) = Model::init(&meta.config, 0)?;
    load_weights(&varmap, &Checkpoint(&dir).weights())?;
    Ok((meta, model, varmap))
}

fn resolve(path: &Path) -> Result<PathBuf> {
    let candidates = [path.to_path_buf(), Run(path).model()];
    candidates
        .iter()
        .filter_map(|c| existing_dir(c))
        .find(|d| Checkpoint(d).config().exists())
        .ok_or_else(|| checkpoint_error(path, "not a checkpoint directory (no config.json in it or in its model/)"))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run of an earlier pvt3 (its stopping rule in another form) still loads, without a rule.
    #[test]
    fn a_stopping_rule_of_another_form_reads_as_none() {
        let p = Provenance {
            pvt3_version: "test".into(),
            data: "d".into(),
            val_fold: Some(0),
            seed: 0,
            epoch: 1,
            val_accuracy: 0.5,
            test_accuracy: None,
            options: TrainOptions::default(),
            pruning: None,
            held_out: None,
            trained_on: None,
            reading: None,
            camera: None,
            stopping: None,
            expected: None,
        };
        let mut json = serde_json::to_value(&p).unwrap();
        json["stopping"] = serde_json::json!({"threshold": 0.9, "full_accuracy": 0.9, "accuracy": 0.9, "mean_share": 0.5});
        assert_eq!(serde_json::from_value::<Provenance>(json.clone()).unwrap().stopping, None);
        let rule =
            serde_json::json!({"rule": {"top_probability": 0.9, "agreeing": 3}, "full_accuracy": 0.9, "accuracy": 0.9, "mean_share": 0.5});
        json["stopping"] = rule;
        assert_eq!(serde_json::from_value::<Provenance>(json).unwrap().stopping.unwrap().rule.agreeing, 3);
    }
}
