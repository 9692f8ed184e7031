//! Tactile data sets: `.npz` files (keys `x`, `y` and optionally `fold`) or directories of
//! `x.npy`, `y.npy` and `fold.npy`, holding frames `[N, H, W, T]`, `[N, C, T]` (read as a C × 1
//! grid) or `[N, H, W, C, T]`, integer labels `[N]` and an optional fold per sample. Any integer
//! or float dtype is accepted and converted to f32.
//!
//! A camera's touches (`pvt3 import` of videos, frame folders or still images) hold 8-bit frames
//! `[N, H, W, C, T]` (grey: `[N, H, W, T]`) and, where each touch's frame before contact is
//! subtracted, that frame as `background` `[N, H, W, (C)]`.
//!
//! Touches of unequal length (what `pvt3 import` writes from CSV folders) hold `lengths` `[N]`:
//! touch `i` is its first `lengths[i]` frames, the rest of `T` padding never read. Optional
//! `class_names` and `sources` (UTF-8 bytes, one name per line) name the classes and each touch's
//! file, for errors and reports. Conditions (`conditions`, then `condition_NAME` per condition:
//! the speed, force or direction of each touch, read by `pvt3 import --name` from file names)
//! let `--hold-out` test on whole levels of a condition the training never saw.
//!
//! The published protocol: fold k validates, fold 4 tests, the other folds train. A set without a
//! fold array gets stratified folds 0..=4 drawn from a seed. Folds are drawn by touch: the
//! windows a model reads from one touch are never split between training and test. A run records
//! the split it trained on ([`split::TrainedOn`]), and every reload takes it from there.
//!
//! The data wing: a sample goes one way, from a file ([`Dataset`], or CSV folders through
//! [`import`]) to a split's windows normalised by the training split's fit ([`normalization`],
//! [`windows`]) to an augmented batch ([`augment`]) to the learner ([`crate::train`]).

use std::borrow::Cow;
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

use crate::{Error, Result};
pub use frames::Frames;

pub mod augment;
mod digest;
mod file;
mod frames;
pub mod import;
pub mod normalization;
mod split;
pub mod windows;
pub use split::{Split, TrainedOn, FOLDS, TEST_FOLD};

/// The arrays of a data set file, as `pvt3 import` writes them and [`Dataset::load`] reads them.
pub mod key {
    pub const X: &str = "x";
    pub const Y: &str = "y";
    pub const FOLD: &str = "fold";
    pub const LENGTHS: &str = "lengths";
    pub const CLASS_NAMES: &str = "class_names";
    pub const SOURCES: &str = "sources";
    pub const CHANNELS: &str = "channels";
    /// The names of the touches' conditions, one a line.
    pub const CONDITIONS: &str = "conditions";
    /// How the touches were read (resampled to one speed, scaled to one force), a JSON
    /// `pvt3_format::Reading`, UTF-8.
    pub const READING: &str = "reading";
    pub const CAMERA: &str = "camera";
    /// The kind of sensor the frames come from, one line (`pvt3_spec::Sensor::name`: `array` or
    /// `camera`), as the import read them.
    pub const SENSOR: &str = "sensor";
    /// Each camera touch's frame before contact, `x`'s shape without its frame axis, which a
    /// reader subtracts from its frames (`pvt3 import --subtract-first`).
    pub const BACKGROUND: &str = "background";

    /// The array of one condition's level for every touch, one a line.
    pub fn condition(name: &str) -> String {
        format!("condition_{name}")
    }
}

/// A condition of the touches (a speed, a force): its name and each touch's level, as text.
#[derive(Clone, Debug, PartialEq)]
pub struct Condition {
    pub name: String,
    pub levels: Vec<String>,
}

impl Condition {
    /// Its distinct levels, in numeric order where every level is a number, else in text order.
    pub fn distinct(&self) -> Vec<&str> {
        self.distinct_among(|_| true)
    }

    /// The distinct levels of the touches `among` takes (by index), ordered as [`Self::distinct`].
    pub fn distinct_among(&self, among: impl Fn(usize) -> bool) -> Vec<&str> {
        let mut all: Vec<&str> = self.levels.iter().enumerate().filter(|&(i, _)| among(i)).map(|(_, l)| l.as_str()).collect();
        all.sort_unstable();
        all.dedup();
        if all.iter().all(|l| l.parse::<f64>().is_ok()) {
            all.sort_by(|a, b| a.parse::<f64>().unwrap_or(0.0).total_cmp(&b.parse::<f64>().unwrap_or(0.0)));
        }
        all
    }
}

/// Touches held out by a condition's levels, the test set of a run ([`Dataset::hold_out`]); the
/// other touches are dealt into the training and validation folds with `seed`. With `class`, only
/// that class's touches of those levels are held out: the other classes train at every level
/// (one fabric's other sliding direction, say, where the others were touched both ways).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct HoldOut {
    pub condition: String,
    pub levels: Vec<String>,
    pub seed: u64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub class: Option<String>,
}

impl HoldOut {
    /// Whether `other` holds out the same touches of a set (whatever seed deals the rest).
    pub fn same_touches(&self, other: &HoldOut) -> bool {
        (&self.condition, &self.levels, &self.class) == (&other.condition, &other.levels, &other.class)
    }
}

impl std::fmt::Display for HoldOut {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}={}", self.condition, self.levels.join(","))?;
        match &self.class {
            Some(class) => write!(f, " of class {class}"),
            None => Ok(()),
        }
    }
}

#[derive(Clone, Debug)]
pub struct Dataset {
    /// Samples back to back, each in the model layout `[H, W, (C,) T]`: f32, or a camera's 8-bit
    /// frames as recorded ([`Frames`]); shared by the copies of a set (each seed's split of a
    /// cross-validation), never copied.
    pub x: Arc<Frames>,
    /// The layout of one sample: `[H, W, T]` or `[H, W, C, T]`; `T` is the longest touch's.
    pub sample_shape: Vec<usize>,
    /// The kind of sensor the frames come from, as the file records it ([`key::SENSOR`]), or
    /// taken by the frames' size where it does not ([`pvt3_spec::Sensor::of`]): what every choice
    /// that differs between kinds reads.
    pub sensor: pvt3_spec::Sensor,
    /// Whether the file records [`Dataset::sensor`] (`false`: it was taken by the frames' size).
    pub sensor_recorded: bool,
    /// Each touch's frames (`T` for all unless the file holds `lengths`).
    pub lengths: Vec<usize>,
    /// Class names from the file (`class_names`), if it has them.
    pub class_names: Option<Vec<String>>,
    /// Where each touch came from (`sources`: the CSV files of `pvt3 import`), if the file says.
    pub sources: Option<Vec<String>>,
    /// The touches' conditions, if the file records them.
    pub conditions: Vec<Condition>,
    /// The levels held out as the test set, if any ([`Dataset::hold_out`]).
    pub held_out: Option<HoldOut>,
    /// How the touches were read, if they were brought to one speed or force (`pvt3 import`).
    pub reading: Option<pvt3_format::Reading>,
    /// How camera frames were read from the camera's (`pvt3 import` of videos or images): the
    /// file's `camera`, a JSON [`pvt3_format::Camera`] on one line.
    pub camera: Option<pvt3_format::Camera>,
    pub labels: Vec<u32>,
    pub folds: Vec<usize>,
    /// The seed that drew the folds (the file had none, or levels are held out); `None`: the
    /// file's own `fold` array.
    pub fold_seed: Option<u64>,
    pub path: PathBuf,
    /// [`Dataset::digest`], once computed.
    pub digest: OnceLock<String>,
}

impl Dataset {
    /// Touches held in memory (`x` the layout `sample_shape` back to back), all in fold 0 and
    /// of full length: what a test builds a data set from.
    #[cfg(test)]
    pub(crate) fn in_memory(x: impl Into<Frames>, sample_shape: Vec<usize>, labels: Vec<u32>) -> Self {
        let frames = *sample_shape.last().expect("a frame axis");
        Self {
            x: Arc::new(x.into()),
            sensor: pvt3_spec::Sensor::of(&sample_shape),
            sensor_recorded: false,
            sample_shape,
            lengths: vec![frames; labels.len()],
            class_names: None,
            sources: None,
            conditions: Vec::new(),
            held_out: None,
            reading: None,
            camera: None,
            folds: vec![0; labels.len()],
            labels,
            fold_seed: None,
            path: PathBuf::from("mem"),
            digest: OnceLock::new(),
        }
    }

    pub fn len(&self) -> usize {
        self.labels.len()
    }

    pub fn is_empty(&self) -> bool {
        self.labels.is_empty()
    }

    pub fn sample_len(&self) -> usize {
        self.sample_shape.iter().product()
    }

    /// Touch `i`'s values, as f32 whatever the file held.
    pub fn sample(&self, i: usize) -> Cow<'_, [f32]> {
        self.x.sample(i, self.sample_len(), self.max_frames())
    }

    /// Frames of the longest touch (the file's `T`).
    pub fn max_frames(&self) -> usize {
        *self.sample_shape.last().expect("a sample shape has a frame axis")
    }

    /// The layout of the longest window every touch that trains or validates holds:
    /// `sample_shape` with the shortest such touch's length. Test touches never shape the model; one
    /// shorter than the window is answered from the tokens it fills ([`Dataset::check_fits`]).
    pub fn window_shape(&self) -> Vec<usize> {
        let mut shape = self.sample_shape.clone();
        let learnt = (0..self.len()).filter(|&i| self.folds[i] != TEST_FOLD);
        *shape.last_mut().expect("a frame axis") = learnt.map(|i| self.lengths[i]).min().unwrap_or(0);
        shape
    }

    /// The test touches shorter than `frames`.
    pub fn short_tests(&self, frames: usize) -> Vec<usize> {
        (0..self.len()).filter(|&i| self.folds[i] == TEST_FOLD && self.lengths[i] < frames).collect()
    }

    /// Whether every touch fills the file's `T` frames.
    pub fn equal_lengths(&self) -> bool {
        self.lengths.iter().all(|l| *l == self.max_frames())
    }

    /// Appends frames `start..start + frames` of touch `i` to `out`, in the sample layout; a
    /// touch that ends before them is continued by its last frame (frames a prefix's answer
    /// never reads).
    pub fn window_into(&self, i: usize, start: usize, frames: usize, out: &mut Vec<f32>) {
        let end = (start + frames).min(self.lengths[i]);
        for row in self.sample(i).chunks(self.max_frames()) {
            out.extend_from_slice(&row[start..end]);
            out.extend(std::iter::repeat_n(row[end - 1], start + frames - end));
        }
    }

    /// How touch `i` is named in errors: its source file, or its index.
    pub fn touch_name(&self, i: usize) -> String {
        match &self.sources {
            Some(s) => format!("touch {i} ({})", s[i]),
            None => format!("touch {i}"),
        }
    }

    /// The label of the class named `name` in the file's class names.
    pub fn class_label(&self, name: &str) -> Result<u32> {
        let names = self
            .class_names
            .as_ref()
            .ok_or_else(|| Error::data(&self.path, format!("class {name}: the set names no classes (pvt3 import writes their names)")))?;
        names
            .iter()
            .position(|n| n == name)
            .map(|c| c as u32)
            .ok_or_else(|| Error::data(&self.path, format!("no class is named {name}; the set's classes are {}", names.join(", "))))
    }

    /// Number of classes: the largest label + 1.
    pub fn classes(&self) -> usize {
        self.labels.iter().max().map_or(0, |m| *m as usize + 1)
    }

    /// A run's split: with a validation fold, [`Dataset::split`]; without one (a final model),
    /// every touch trains and none validates or tests.
    pub fn split_for(&self, val_fold: Option<usize>) -> Result<Split> {
        match val_fold {
            Some(k) => self.split(k),
            None => Ok(Split { train: (0..self.len()).collect(), val: Vec::new(), test: Vec::new() }),
        }
    }

    /// The published protocol for validation fold `val_fold`: test on fold 4, train on the rest.
    pub fn split(&self, val_fold: usize) -> Result<Split> {
        if val_fold >= TEST_FOLD {
            return Err(Error::Usage(format!("validation fold {val_fold} must be in 0..{TEST_FOLD}")));
        }
        let pick = |keep: &dyn Fn(usize) -> bool| (0..self.len()).filter(|&i| keep(self.folds[i])).collect::<Vec<_>>();
        let split =
            Split { train: pick(&|f| f != val_fold && f != TEST_FOLD), val: pick(&|f| f == val_fold), test: pick(&|f| f == TEST_FOLD) };
        if split.train.is_empty() || split.val.is_empty() {
            return Err(Error::data(&self.path, format!("fold {val_fold} leaves no training or validation samples")));
        }
        Ok(split)
    }

    /// Loads a data set as a run was trained on it: the split it recorded (refusing other
    /// touches), or for a run of a pvt3 that recorded none, the split derived as it was then:
    /// `seed` draws folds where the file has none, and the run's held-out levels are held out again.
    pub fn load_as_trained(path: &Path, seed: u64, held_out: Option<&HoldOut>, recorded: Option<&TrainedOn>) -> Result<Self> {
        let mut data = Self::load(path, seed)?;
        if let Some(h) = held_out {
            data.hold_out(h)?;
        }
        if let Some(recorded) = recorded {
            data.take_split(recorded)?;
        }
        Ok(data)
    }

    /// This data set with its folds drawn from `seed` where they are drawn (no fold array, or
    /// levels held out), as each seed of a cross-validation draws its own; `None` where the folds
    /// are the file's, the same for every seed.
    pub fn reseeded(&self, seed: u64) -> Result<Option<Self>> {
        if self.fold_seed.is_none() {
            return Ok(None);
        }
        let mut data = self.clone();
        match &self.held_out {
            Some(h) => data.hold_out(&HoldOut { seed, ..h.clone() })?,
            None => {
                data.folds = split::stratified_folds(&data.labels, FOLDS, seed);
                data.fold_seed = Some(seed);
            }
        }
        Ok(Some(data))
    }

    /// Tests on whole levels of a condition: the touches whose condition has one of the levels
    /// become the test fold, never trained or validated on; the others are dealt, stratified by
    /// class with the hold-out's seed, into the folds that train and validate.
    pub fn hold_out(&mut self, h: &HoldOut) -> Result<()> {
        let (name, levels, seed) = (h.condition.as_str(), &h.levels, h.seed);
        let known = || self.conditions.iter().map(|c| c.name.as_str()).collect::<Vec<_>>().join(", ");
        let condition = self.conditions.iter().find(|c| c.name == name).ok_or_else(|| {
            if self.conditions.is_empty() {
                Error::data(
                    &self.path,
                    format!("--hold-out {name}: the set records no conditions (pvt3 import --name reads them from file names)"),
                )
            } else {
                Error::data(&self.path, format!("--hold-out {name}: no such condition; the set records {}", known()))
            }
        })?;
        let all = condition.distinct();
        if let Some(bad) = levels.iter().find(|l| !all.contains(&l.as_str())) {
            return Err(Error::data(
                &self.path,
                format!("--hold-out {name}={bad}: no touch has that level; {name} has {}", all.join(", ")),
            ));
        }
        let class = h.class.as_deref().map(|c| self.class_label(c)).transpose()?;
        let held: Vec<bool> =
            condition.levels.iter().zip(&self.labels).map(|(l, y)| levels.contains(l) && class.is_none_or(|c| c == *y)).collect();
        let kept: Vec<usize> = (0..self.len()).filter(|&i| !held[i]).collect();
        let kept_labels: Vec<u32> = kept.iter().map(|&i| self.labels[i]).collect();
        for c in 0..self.classes() as u32 {
            let n = kept_labels.iter().filter(|l| **l == c).count();
            if n < TEST_FOLD {
                return Err(Error::data(
                    &self.path,
                    format!("--hold-out {h}: class {c} keeps {n} touches, too few to train and validate on {TEST_FOLD} folds"),
                ));
            }
        }
        if held.iter().all(|h| !h) {
            return Err(Error::data(&self.path, format!("--hold-out {h}: holds out no touch")));
        }
        let folds = split::stratified_folds(&kept_labels, TEST_FOLD, seed);
        for (k, &i) in kept.iter().enumerate() {
            self.folds[i] = folds[k];
        }
        (0..self.len()).filter(|&i| held[i]).for_each(|i| self.folds[i] = TEST_FOLD);
        self.held_out = Some(h.clone());
        self.fold_seed = Some(seed);
        Ok(())
    }

    /// Checks that the samples fit a model configuration: the same frame layout, and every touch
    /// that trains or validates at least the model's window long (a longer touch is read a window
    /// at a time). A test touch may be shorter: PVT³ answers it from the temporal tokens it fills,
    /// as a robot's stream peeks when the touch ends before the window, if it fills one.
    pub fn check_fits(&self, cfg: &pvt3_models::Config) -> Result<()> {
        let expected = cfg.sample_shape();
        let (frame, model_frame) = (&self.sample_shape[..self.sample_shape.len() - 1], &expected[..expected.len() - 1]);
        if frame != model_frame || (self.equal_lengths() && self.max_frames() < cfg.frames) {
            return Err(Error::data(
                &self.path,
                format!("samples are {:?} but the model expects {:?} ([height, width, (channels,) frames])", self.sample_shape, expected),
            ));
        }
        let short_test = |i: usize| {
            self.folds[i] == TEST_FOLD && self.lengths[i] >= cfg.tubelet && cfg.architecture() == pvt3_models::Architecture::Pvt3
        };
        if let Some(i) = (0..self.len()).find(|&i| self.lengths[i] < cfg.frames && !short_test(i)) {
            return Err(Error::data(
                &self.path,
                format!(
                    "{} has {} frames, fewer than the model's window of {}: leave it out, or train a shorter window (--set frames=N)",
                    self.touch_name(i),
                    self.lengths[i],
                    cfg.frames
                ),
            ));
        }
        if let Some(bad) = self.labels.iter().find(|l| **l as usize >= cfg.classes) {
            return Err(Error::data(&self.path, format!("label {bad} is outside 0..{} of the model's classes", cfg.classes)));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
