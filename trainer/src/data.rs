//! Tactile data sets: `.npz` files (keys `x`, `y` and optionally `fold`) or directories of
//! `x.npy`, `y.npy` and `fold.npy`, holding frames `[N, H, W, T]`, `[N, C, T]` (read as a C × 1
//! grid) or `[N, H, W, C, T]`, integer labels `[N]` and an optional fold per sample. Any integer
//! or float dtype is accepted and converted to f32.
//!
//! A camera's touches (`pvt3 import` of videos or frame folders) hold 8-bit frames
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
use std::fs::File;
use std::io::{Read, Seek};
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

use ndarray::{ArrayD, IxDyn};
use ndarray_npy::{NpzReader, ReadNpyExt, ReadableElement};
use pvt3_models::Rng;

use crate::{Error, Result};
pub use frames::Frames;

pub mod augment;
mod frames;
pub mod import;
pub mod normalization;
mod split;
pub mod windows;
pub use split::{Split, TrainedOn};

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

/// The fold that holds the test set in the published protocol.
pub const TEST_FOLD: usize = 4;
/// Folds 0..FOLDS (the test fold included).
pub const FOLDS: usize = 5;

#[derive(Clone, Debug)]
pub struct Dataset {
    /// Samples back to back, each in the model layout `[H, W, (C,) T]`: f32, or a camera's 8-bit
    /// frames as recorded ([`Frames`]); shared by the copies of a set (each seed's split of a
    /// cross-validation), never copied.
    pub x: Arc<Frames>,
    /// The layout of one sample: `[H, W, T]` or `[H, W, C, T]`; `T` is the longest touch's.
    pub sample_shape: Vec<usize>,
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

fn data_error(path: &Path, reason: impl Into<String>) -> Error {
    Error::Data { path: path.to_path_buf(), reason: reason.into() }
}

/// Reads an array of any of the common numeric dtypes as f64.
trait ArraySource {
    fn read<T: ReadableElement>(&mut self, key: &str) -> std::result::Result<ArrayD<T>, String>;
    fn keys(&mut self) -> Vec<String>;
}

struct Npz<R: Read + Seek>(NpzReader<R>);

impl<R: Read + Seek> ArraySource for Npz<R> {
    fn read<T: ReadableElement>(&mut self, key: &str) -> std::result::Result<ArrayD<T>, String> {
        let name = if self.keys().iter().any(|k| k == key) { key.to_string() } else { format!("{key}.npy") };
        self.0.by_name::<ndarray::OwnedRepr<T>, IxDyn>(&name).map_err(|e| e.to_string())
    }
    fn keys(&mut self) -> Vec<String> {
        self.0.names().unwrap_or_default().into_iter().map(|n| n.trim_end_matches(".npy").to_string()).collect()
    }
}

struct NpyDir(PathBuf);

impl ArraySource for NpyDir {
    fn read<T: ReadableElement>(&mut self, key: &str) -> std::result::Result<ArrayD<T>, String> {
        let file = File::open(self.0.join(format!("{key}.npy"))).map_err(|e| e.to_string())?;
        ArrayD::<T>::read_npy(std::io::BufReader::new(file)).map_err(|e| e.to_string())
    }
    fn keys(&mut self) -> Vec<String> {
        let entries = std::fs::read_dir(&self.0).into_iter().flatten().flatten();
        entries.filter_map(|e| e.file_name().to_str()?.strip_suffix(".npy").map(str::to_string)).collect()
    }
}

/// Reads `key` whatever its numeric dtype, as f64.
fn read_numeric(src: &mut impl ArraySource, key: &str) -> std::result::Result<ArrayD<f64>, String> {
    fn conv<T: Copy + Into<f64>>(a: ArrayD<T>) -> ArrayD<f64> {
        a.mapv(Into::into)
    }
    let mut first_error = None;
    macro_rules! attempt {
        ($($t:ty),*) => {$(
            match src.read::<$t>(key) {
                Ok(a) => return Ok(conv(a)),
                Err(e) => { first_error.get_or_insert(e); }
            }
        )*};
    }
    attempt!(f32, f64, i16, u8, i8, u16, i32, u32);
    // 64-bit integers do not convert losslessly to f64 in general; labels and folds are small.
    if let Ok(a) = src.read::<i64>(key) {
        return Ok(a.mapv(|v| v as f64));
    }
    if let Ok(a) = src.read::<u64>(key) {
        return Ok(a.mapv(|v| v as f64));
    }
    Err(first_error.unwrap_or_default())
}

/// `x` and its shape: 8-bit frames as they are, beside their background where the file has one
/// (`key::BACKGROUND`, one frame a touch), which a reader subtracts ([`Frames`]); any other dtype
/// as f32, minus its background.
fn read_frames(path: &Path, src: &mut impl ArraySource, has_background: bool) -> Result<(Frames, Vec<usize>)> {
    let eight_bit = src.read::<u8>(key::X).ok();
    let background = if has_background && eight_bit.is_some() { src.read::<u8>(key::BACKGROUND).ok() } else { None };
    if let Some(x) = eight_bit.filter(|_| has_background == background.is_some()) {
        let shape = x.shape().to_vec();
        if let Some(b) = &background {
            check_background(path, &shape, b.shape())?;
        }
        return Ok((Frames::U8 { x: flat(x), background: background.map(flat) }, shape));
    }
    let mut x = read_numeric(src, key::X).map_err(|e| data_error(path, format!("array `x`: {e}")))?;
    if has_background {
        let b = read_numeric(src, key::BACKGROUND).map_err(|e| data_error(path, format!("array `background`: {e}")))?;
        check_background(path, x.shape(), b.shape())?;
        x -= &b.insert_axis(ndarray::Axis(x.ndim() - 1));
    }
    let shape = x.shape().to_vec();
    let x: Vec<f32> = x.iter().map(|v| *v as f32).collect();
    let sample_len = x.len() / shape.first().copied().unwrap_or(1).max(1);
    if let Some(i) = x.iter().position(|v| !v.is_finite()) {
        return Err(data_error(path, format!("`x` holds a NaN or infinite value in sample {}", i / sample_len)));
    }
    Ok((Frames::F32(x), shape))
}

/// A background is a frame of each touch: `x`'s shape (`[N, H, W, C, T]`) without its frame axis.
fn check_background(path: &Path, x: &[usize], background: &[usize]) -> Result<()> {
    if x.len() < 2 {
        return Err(data_error(path, format!("`x` has shape {x:?}; a background needs touches of frames")));
    }
    let frame = &x[..x.len() - 1];
    if background != frame {
        return Err(data_error(path, format!("`background` has shape {background:?}; expected {frame:?}, `x`'s without its frame axis")));
    }
    Ok(())
}

/// An array's values in row-major order, without a copy where they already are.
fn flat<T: Clone>(a: ArrayD<T>) -> Vec<T> {
    if a.is_standard_layout() {
        a.into_raw_vec_and_offset().0
    } else {
        a.iter().cloned().collect()
    }
}

impl Dataset {
    /// Loads a data set; `seed` draws stratified folds when the file has none.
    pub fn load(path: &Path, seed: u64) -> Result<Self> {
        if !path.exists() {
            return Err(data_error(path, "no such file or directory (expected an .npz file or a directory of .npy files)"));
        }
        if path.is_dir() {
            Self::from_source(path, &mut NpyDir(path.to_path_buf()), seed)
        } else {
            let file = File::open(path).map_err(Error::io(path))?;
            let npz = NpzReader::new(std::io::BufReader::new(file))
                .map_err(|e| data_error(path, format!("not a readable .npz archive ({e})")))?;
            Self::from_source(path, &mut Npz(npz), seed)
        }
    }

    fn from_source(path: &Path, src: &mut impl ArraySource, seed: u64) -> Result<Self> {
        let keys = src.keys();
        let missing = |k: &str| data_error(path, format!("no array `{k}` (found: {})", keys.join(", ")));
        for k in [key::X, key::Y] {
            if !keys.iter().any(|have| have == k) {
                return Err(missing(k));
            }
        }
        let (x, shape) = read_frames(path, src, keys.iter().any(|k| k == key::BACKGROUND))?;
        let y = read_numeric(src, key::Y).map_err(|e| data_error(path, format!("array `y`: {e}")))?;
        let fold = if keys.iter().any(|k| k == key::FOLD) {
            Some(read_numeric(src, key::FOLD).map_err(|e| data_error(path, format!("array `fold`: {e}")))?)
        } else {
            None
        };
        let sample_shape = match shape[..] {
            [_, c, t] => vec![c, 1, t],
            [_, h, w, t] => vec![h, w, t],
            [_, h, w, c, t] => vec![h, w, c, t],
            _ => return Err(data_error(path, format!("`x` has shape {shape:?}; expected [N, H, W, T], [N, C, T] or [N, H, W, C, T]"))),
        };
        let n = shape[0];
        let labels = integers(path, key::Y, &y, n)?;
        let frames = *sample_shape.last().expect("a sample shape has a frame axis");
        let lengths = if keys.iter().any(|k| k == key::LENGTHS) {
            let l = read_numeric(src, key::LENGTHS).map_err(|e| data_error(path, format!("array `lengths`: {e}")))?;
            let lengths = integers(path, key::LENGTHS, &l, n)?;
            if let Some(i) = lengths.iter().position(|l| *l == 0 || *l as usize > frames) {
                return Err(data_error(path, format!("`lengths`[{i}] = {} is not in 1..={frames}", lengths[i])));
            }
            lengths.into_iter().map(|l| l as usize).collect()
        } else {
            vec![frames; n]
        };
        // The lines of a text array; `count`, how many it must have.
        let mut lines = |key: &str, count: Option<usize>| -> Result<Option<Vec<String>>> {
            if !keys.iter().any(|k| k == key) {
                return Ok(None);
            }
            let bytes = src.read::<u8>(key).map_err(|e| data_error(path, format!("array `{key}` (UTF-8 bytes): {e}")))?;
            let text = String::from_utf8(bytes.iter().copied().collect())
                .map_err(|_| data_error(path, format!("array `{key}` is not UTF-8 text")))?;
            let names: Vec<String> = text.lines().map(String::from).collect();
            if let Some(count) = count.filter(|c| *c != names.len()) {
                return Err(data_error(path, format!("array `{key}` names {} lines; expected {count}", names.len())));
            }
            Ok(Some(names))
        };
        let classes = labels.iter().max().map_or(0, |m| *m as usize + 1);
        let class_names = lines(key::CLASS_NAMES, Some(classes))?;
        let sources = lines(key::SOURCES, Some(n))?;
        let mut conditions = Vec::new();
        for name in lines(key::CONDITIONS, None)?.unwrap_or_default() {
            let levels = lines(&key::condition(&name), Some(n))?.ok_or_else(|| missing(&key::condition(&name)))?;
            conditions.push(Condition { name, levels });
        }
        // A record of one JSON line: how the touches, or a camera's frames, were read.
        fn record<T: serde::de::DeserializeOwned>(path: &Path, key: &str, what: &str, text: Option<Vec<String>>) -> Result<Option<T>> {
            let parse =
                |line: &String| serde_json::from_str(line).map_err(|e| data_error(path, format!("array `{key}` is not {what} ({e})")));
            text.as_ref().map(|t| parse(&t[0])).transpose()
        }
        let reading = record(path, key::READING, "how touches are read", lines(key::READING, Some(1))?)?;
        let camera = record(path, key::CAMERA, "how camera frames are read", lines(key::CAMERA, Some(1))?)?;
        let (folds, fold_seed) = match fold {
            Some(f) => {
                let folds = integers(path, key::FOLD, &f, n)?;
                if let Some(bad) = folds.iter().find(|f| **f as usize >= FOLDS) {
                    return Err(data_error(path, format!("fold {bad} is outside 0..={}", FOLDS - 1)));
                }
                (folds.into_iter().map(|f| f as usize).collect(), None)
            }
            None => (stratified_folds(&labels, FOLDS, seed), Some(seed)),
        };
        Ok(Self {
            x: Arc::new(x),
            sample_shape,
            lengths,
            class_names,
            sources,
            conditions,
            held_out: None,
            reading,
            camera,
            labels: labels.to_vec(),
            folds,
            fold_seed,
            path: path.to_path_buf(),
            digest: OnceLock::new(),
        })
    }

    /// Touches held in memory (`x` the layout `sample_shape` back to back), all in fold 0 and
    /// of full length: what a test builds a data set from.
    #[cfg(test)]
    pub(crate) fn in_memory(x: impl Into<Frames>, sample_shape: Vec<usize>, labels: Vec<u32>) -> Self {
        let frames = *sample_shape.last().expect("a frame axis");
        Self {
            x: Arc::new(x.into()),
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
            .ok_or_else(|| data_error(&self.path, format!("class {name}: the set names no classes (pvt3 import writes their names)")))?;
        names
            .iter()
            .position(|n| n == name)
            .map(|c| c as u32)
            .ok_or_else(|| data_error(&self.path, format!("no class is named {name}; the set's classes are {}", names.join(", "))))
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
            return Err(data_error(&self.path, format!("fold {val_fold} leaves no training or validation samples")));
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
                data.folds = stratified_folds(&data.labels, FOLDS, seed);
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
                data_error(
                    &self.path,
                    format!("--hold-out {name}: the set records no conditions (pvt3 import --name reads them from file names)"),
                )
            } else {
                data_error(&self.path, format!("--hold-out {name}: no such condition; the set records {}", known()))
            }
        })?;
        let all = condition.distinct();
        if let Some(bad) = levels.iter().find(|l| !all.contains(&l.as_str())) {
            return Err(data_error(&self.path, format!("--hold-out {name}={bad}: no touch has that level; {name} has {}", all.join(", "))));
        }
        let class = h.class.as_deref().map(|c| self.class_label(c)).transpose()?;
        let held: Vec<bool> =
            condition.levels.iter().zip(&self.labels).map(|(l, y)| levels.contains(l) && class.is_none_or(|c| c == *y)).collect();
        let kept: Vec<usize> = (0..self.len()).filter(|&i| !held[i]).collect();
        let kept_labels: Vec<u32> = kept.iter().map(|&i| self.labels[i]).collect();
        for c in 0..self.classes() as u32 {
            let n = kept_labels.iter().filter(|l| **l == c).count();
            if n < TEST_FOLD {
                return Err(data_error(
                    &self.path,
                    format!("--hold-out {h}: class {c} keeps {n} touches, too few to train and validate on {TEST_FOLD} folds"),
                ));
            }
        }
        if held.iter().all(|h| !h) {
            return Err(data_error(&self.path, format!("--hold-out {h}: holds out no touch")));
        }
        let folds = stratified_folds(&kept_labels, TEST_FOLD, seed);
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
            return Err(data_error(
                &self.path,
                format!("samples are {:?} but the model expects {:?} ([height, width, (channels,) frames])", self.sample_shape, expected),
            ));
        }
        let short_test = |i: usize| {
            self.folds[i] == TEST_FOLD && self.lengths[i] >= cfg.tubelet && cfg.architecture() == pvt3_models::Architecture::Pvt3
        };
        if let Some(i) = (0..self.len()).find(|&i| self.lengths[i] < cfg.frames && !short_test(i)) {
            return Err(data_error(
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
            return Err(data_error(&self.path, format!("label {bad} is outside 0..{} of the model's classes", cfg.classes)));
        }
        Ok(())
    }
}

/// Converts a numeric array of `n` whole, non-negative values to u32.
fn integers(path: &Path, key: &str, a: &ArrayD<f64>, n: usize) -> Result<Vec<u32>> {
    if a.shape() != [n] {
        return Err(data_error(path, format!("`{key}` has shape {:?}; expected [{n}], one per sample", a.shape())));
    }
    a.iter()
        .enumerate()
        .map(|(i, v)| {
            if v.fract() == 0.0 && *v >= 0.0 && *v <= u32::MAX as f64 {
                Ok(*v as u32)
            } else {
                Err(data_error(path, format!("`{key}`[{i}] = {v} is not a whole number ≥ 0")))
            }
        })
        .collect()
}

/// Deals each class's samples, shuffled by `seed`, round-robin into folds 0..folds_count.
fn stratified_folds(labels: &[u32], folds_count: usize, seed: u64) -> Vec<usize> {
    let mut rng = Rng::new(seed);
    let mut folds = vec![0; labels.len()];
    let classes = labels.iter().max().map_or(0, |m| *m + 1);
    for c in 0..classes {
        let mut members: Vec<usize> = (0..labels.len()).filter(|&i| labels[i] == c).collect();
        rng.shuffle(&mut members);
        for (k, i) in members.into_iter().enumerate() {
            folds[i] = k % folds_count;
        }
    }
    folds
}

#[cfg(test)]
mod tests;
