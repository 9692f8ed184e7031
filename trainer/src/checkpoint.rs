//! Checkpoints are directories of files named in [`crate::run_dir::Checkpoint`]: configuration,
//! weights, normalisation, class names and provenance (and in a run's `last/`, what resuming
//! needs besides), each replaced whole ([`crate::atomic::dir::replace_dir`]), so a crash never leaves a
//! half-written checkpoint.

use std::path::{Path, PathBuf};

use candle_nn::VarMap;
use pvt3_models::weights::{load_weights, save_weights};
use pvt3_models::{Config, Model};
use serde::{Deserialize, Serialize};

use crate::atomic::dir::{existing_dir, replace_dir};
use crate::data::normalization::Normalization;
use crate::json::{read_json, write_json};
use crate::provenance::Provenance;
use crate::run_dir::{Checkpoint, Run};
use crate::{Error, Result};

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
