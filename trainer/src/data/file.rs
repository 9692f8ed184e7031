//! A data file's arrays, an `.npz` archive or a folder of `.npy` files (the layout of
//! [`crate::data`]'s docs), read into a [`Dataset`] and checked on the way: each refusal names
//! the file and the array.

use std::fs::File;
use std::io::{Read, Seek};
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

use ndarray::{ArrayD, IxDyn};
use ndarray_npy::{NpzReader, ReadNpyExt, ReadableElement};

use super::split::stratified_folds;
use super::{key, Condition, Dataset, Frames, FOLDS};
use crate::{Error, Result};

impl Dataset {
    /// Loads a data set; `seed` draws stratified folds when the file has none.
    pub fn load(path: &Path, seed: u64) -> Result<Self> {
        read(path, seed)
    }
}

/// The data set at `path`; `seed` draws stratified folds when the file has none.
fn read(path: &Path, seed: u64) -> Result<Dataset> {
    if !path.exists() {
        return Err(Error::data(path, "no such file or directory (expected an .npz file or a directory of .npy files)"));
    }
    if path.is_dir() {
        dataset(path, &mut NpyDir(path.to_path_buf()), seed)
    } else {
        let file = File::open(path).map_err(Error::io(path))?;
        let npz =
            NpzReader::new(std::io::BufReader::new(file)).map_err(|e| Error::data(path, format!("not a readable .npz archive ({e})")))?;
        dataset(path, &mut Npz(npz), seed)
    }
}

fn dataset(path: &Path, src: &mut impl ArraySource, seed: u64) -> Result<Dataset> {
    let mut a = Arrays { path, keys: src.keys(), src };
    for k in [key::X, key::Y] {
        if !a.has(k) {
            return Err(a.missing(k));
        }
    }
    let (x, shape) = read_frames(&mut a)?;
    let y = a.numeric(key::Y)?;
    let fold = if a.has(key::FOLD) { Some(a.numeric(key::FOLD)?) } else { None };
    let sample_shape = sample_shape(path, &shape)?;
    let n = shape[0];
    let labels = integers(path, key::Y, &y, n)?;
    let frames = *sample_shape.last().expect("a sample shape has a frame axis");
    let lengths = lengths(&mut a, n, frames)?;
    let classes = labels.iter().max().map_or(0, |m| *m as usize + 1);
    let class_names = a.lines(key::CLASS_NAMES, Some(classes))?;
    let sources = a.lines(key::SOURCES, Some(n))?;
    let mut conditions = Vec::new();
    for name in a.lines(key::CONDITIONS, None)?.unwrap_or_default() {
        let levels = a.lines(&key::condition(&name), Some(n))?.ok_or_else(|| a.missing(&key::condition(&name)))?;
        conditions.push(Condition { name, levels });
    }
    let reading = a.record(key::READING, "how touches are read")?;
    let camera = a.record(key::CAMERA, "how camera frames are read")?;
    let sensor = match a.lines(key::SENSOR, Some(1))? {
        Some(line) => Some(
            pvt3_spec::Sensor::from_name(&line[0])
                .ok_or_else(|| Error::data(path, format!("array `{}` says `{}`: expected `array` or `camera`", key::SENSOR, line[0])))?,
        ),
        None => None,
    };
    let (folds, fold_seed) = match fold {
        Some(f) => (folds(path, &f, n)?, None),
        None => (stratified_folds(&labels, FOLDS, seed), Some(seed)),
    };
    Ok(Dataset {
        x: Arc::new(x),
        sensor: sensor.unwrap_or_else(|| pvt3_spec::Sensor::of(&sample_shape)),
        sensor_recorded: sensor.is_some(),
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

/// One sample's shape, `[H, W, (C,) T]`, from `x`'s; `[N, C, T]` is read as a C × 1 grid.
fn sample_shape(path: &Path, shape: &[usize]) -> Result<Vec<usize>> {
    match shape[..] {
        [_, c, t] => Ok(vec![c, 1, t]),
        [_, h, w, t] => Ok(vec![h, w, t]),
        [_, h, w, c, t] => Ok(vec![h, w, c, t]),
        _ => Err(Error::data(path, format!("`x` has shape {shape:?}; expected [N, H, W, T], [N, C, T] or [N, H, W, C, T]"))),
    }
}

/// Each touch's length in frames: `lengths` where the file has it (each in 1..=`frames`), else
/// every touch the whole window.
fn lengths(a: &mut Arrays<'_, impl ArraySource>, n: usize, frames: usize) -> Result<Vec<usize>> {
    if !a.has(key::LENGTHS) {
        return Ok(vec![frames; n]);
    }
    let lengths = integers(a.path, key::LENGTHS, &a.numeric(key::LENGTHS)?, n)?;
    if let Some(i) = lengths.iter().position(|l| *l == 0 || *l as usize > frames) {
        return Err(Error::data(a.path, format!("`lengths`[{i}] = {} is not in 1..={frames}", lengths[i])));
    }
    Ok(lengths.into_iter().map(|l| l as usize).collect())
}

/// The file's own folds, each in 0..[`FOLDS`].
fn folds(path: &Path, fold: &ArrayD<f64>, n: usize) -> Result<Vec<usize>> {
    let folds = integers(path, key::FOLD, fold, n)?;
    if let Some(bad) = folds.iter().find(|f| **f as usize >= FOLDS) {
        return Err(Error::data(path, format!("fold {bad} is outside 0..={}", FOLDS - 1)));
    }
    Ok(folds.into_iter().map(|f| f as usize).collect())
}

/// The arrays of one file, read by name.
struct Arrays<'a, S> {
    path: &'a Path,
    src: &'a mut S,
    keys: Vec<String>,
}

impl<S: ArraySource> Arrays<'_, S> {
    fn has(&self, key: &str) -> bool {
        self.keys.iter().any(|k| k == key)
    }

    fn missing(&self, key: &str) -> Error {
        Error::data(self.path, format!("no array `{key}` (found: {})", self.keys.join(", ")))
    }

    fn numeric(&mut self, key: &str) -> Result<ArrayD<f64>> {
        read_numeric(self.src, key).map_err(|e| Error::data(self.path, format!("array `{key}`: {e}")))
    }

    /// The lines of a text array (UTF-8 bytes), if the file has it; `count`, how many it must have.
    fn lines(&mut self, key: &str, count: Option<usize>) -> Result<Option<Vec<String>>> {
        if !self.has(key) {
            return Ok(None);
        }
        let path = self.path;
        let bytes = self.src.read::<u8>(key).map_err(|e| Error::data(path, format!("array `{key}` (UTF-8 bytes): {e}")))?;
        let text = String::from_utf8(bytes.iter().copied().collect())
            .map_err(|_| Error::data(path, format!("array `{key}` is not UTF-8 text")))?;
        let names: Vec<String> = text.lines().map(String::from).collect();
        if let Some(count) = count.filter(|c| *c != names.len()) {
            return Err(Error::data(path, format!("array `{key}` names {} lines; expected {count}", names.len())));
        }
        Ok(Some(names))
    }

    /// A record of one JSON line (how the touches, or a camera's frames, were read), if the
    /// file has it; `what` it is, for the error.
    fn record<T: serde::de::DeserializeOwned>(&mut self, key: &str, what: &str) -> Result<Option<T>> {
        let path = self.path;
        let parse = |line: &String| serde_json::from_str(line).map_err(|e| Error::data(path, format!("array `{key}` is not {what} ({e})")));
        self.lines(key, Some(1))?.as_ref().map(|t| parse(&t[0])).transpose()
    }
}

/// Reads an array of any of the common numeric dtypes as f64.
trait ArraySource {
    fn read<T: ReadableElement>(&mut self, key: &str) -> std::result::Result<ArrayD<T>, String>;
    fn keys(&mut self) -> Vec<String>;
}

struct Npz<R: Read + Seek>(NpzReader<R>);

impl<R: Read + Seek> ArraySource for Npz<R> {
    /// The member `key`, or else `key.npy` (`NpzReader::by_name` tries both, in that order).
    fn read<T: ReadableElement>(&mut self, key: &str) -> std::result::Result<ArrayD<T>, String> {
        self.0.by_name::<ndarray::OwnedRepr<T>, IxDyn>(key).map_err(|e| e.to_string())
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
fn read_frames(a: &mut Arrays<'_, impl ArraySource>) -> Result<(Frames, Vec<usize>)> {
    let (path, has_background) = (a.path, a.has(key::BACKGROUND));
    let eight_bit = a.src.read::<u8>(key::X).ok();
    let background = if has_background && eight_bit.is_some() { a.src.read::<u8>(key::BACKGROUND).ok() } else { None };
    if let Some(x) = eight_bit.filter(|_| has_background == background.is_some()) {
        let shape = x.shape().to_vec();
        if let Some(b) = &background {
            check_background(path, &shape, b.shape())?;
        }
        return Ok((Frames::U8 { x: flat(x), background: background.map(flat) }, shape));
    }
    let mut x = a.numeric(key::X)?;
    if has_background {
        let b = a.numeric(key::BACKGROUND)?;
        check_background(path, x.shape(), b.shape())?;
        x -= &b.insert_axis(ndarray::Axis(x.ndim() - 1));
    }
    let shape = x.shape().to_vec();
    let x: Vec<f32> = x.iter().map(|v| *v as f32).collect();
    let sample_len = x.len() / shape.first().copied().unwrap_or(1).max(1);
    if let Some(i) = x.iter().position(|v| !v.is_finite()) {
        return Err(Error::data(path, format!("`x` holds a NaN or infinite value in sample {}", i / sample_len)));
    }
    Ok((Frames::F32(x), shape))
}

/// A background is a frame of each touch: `x`'s shape (`[N, H, W, C, T]`) without its frame axis.
fn check_background(path: &Path, x: &[usize], background: &[usize]) -> Result<()> {
    if x.len() < 2 {
        return Err(Error::data(path, format!("`x` has shape {x:?}; a background needs touches of frames")));
    }
    let frame = &x[..x.len() - 1];
    if background != frame {
        return Err(Error::data(path, format!("`background` has shape {background:?}; expected {frame:?}, `x`'s without its frame axis")));
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

/// Converts a numeric array of `n` whole, non-negative values to u32.
fn integers(path: &Path, key: &str, a: &ArrayD<f64>, n: usize) -> Result<Vec<u32>> {
    if a.shape() != [n] {
        return Err(Error::data(path, format!("`{key}` has shape {:?}; expected [{n}], one per sample", a.shape())));
    }
    a.iter()
        .enumerate()
        .map(|(i, v)| {
            if v.fract() == 0.0 && *v >= 0.0 && *v <= u32::MAX as f64 {
                Ok(*v as u32)
            } else {
                Err(Error::data(path, format!("`{key}`[{i}] = {v} is not a whole number ≥ 0")))
            }
        })
        .collect()
}
