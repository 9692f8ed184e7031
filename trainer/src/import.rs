//! `pvt3 import`: a folder of CSV recordings → a data set (`.npz`) the trainer reads.
//!
//! The folder holds one folder per class (its name is the class's), each with one CSV file per
//! touch: a header row, then one row per frame. Which columns are sensor channels is chosen by
//! name or pattern, or by default every numeric column that varies, time-stamp-like columns
//! left out (and said so). Touches may differ in length; the set records each touch's
//! (`lengths`), its file (`sources`) and the class names (`class_names`), see [`crate::data`].

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use ndarray::{Array1, ArrayD, IxDyn};
use ndarray_npy::NpzWriter;

use crate::data::FOLDS;
use crate::{Error, Result};

/// What to import and how.
#[derive(Clone, Debug, Default)]
pub struct ImportOptions {
    /// Column names or patterns (`*` any run of characters, `?` one), in the order given; empty:
    /// every numeric column that varies, time-stamp-like ones left out.
    pub columns: Vec<String>,
    /// The sensor's grid, rows × columns of the chosen channels (row-major); `None`: one column of
    /// channels (`[N, channels, frames]`, read as a channels × 1 grid).
    pub grid: Option<(usize, usize)>,
}

/// One touch as read: its class, its file, its frames `[frames][columns]` (every column of the
/// header; non-numeric cells are `None`).
struct Touch {
    class: usize,
    path: PathBuf,
    rows: Vec<Vec<Option<f64>>>,
    /// The file line of each row, for errors.
    lines: Vec<u64>,
}

/// The imported set, before it is written.
#[derive(Debug)]
pub struct Imported {
    /// `[touches][channel][frame]`, each touch its own length.
    pub touches: Vec<Vec<Vec<f32>>>,
    pub labels: Vec<u32>,
    pub classes: Vec<String>,
    pub sources: Vec<String>,
    /// The chosen columns, in channel order.
    pub channels: Vec<String>,
    /// Columns left out, each with why.
    pub left_out: LeftOut,
    pub grid: Option<(usize, usize)>,
}

/// Columns left out of an import, each with why.
pub type LeftOut = Vec<(String, &'static str)>;

fn import_error(path: &Path, line: Option<u64>, reason: impl Into<String>) -> Error {
    let place = match line {
        Some(l) => format!("{}:{l}", path.display()),
        None => path.display().to_string(),
    };
    Error::Usage(format!("{place}: {}", reason.into()))
}

/// Whether `name` matches `pattern` (`*`: any run of characters, `?`: one).
pub fn matches(pattern: &str, name: &str) -> bool {
    fn go(p: &[char], n: &[char]) -> bool {
        match p.split_first() {
            None => n.is_empty(),
            Some(('*', rest)) => (0..=n.len()).any(|k| go(rest, &n[k..])),
            Some(('?', rest)) => !n.is_empty() && go(rest, &n[1..]),
            Some((c, rest)) => n.first() == Some(c) && go(rest, &n[1..]),
        }
    }
    go(&pattern.chars().collect::<Vec<_>>(), &name.chars().collect::<Vec<_>>())
}

/// A column whose name says it is a time (`time`, `stamp`, `secs`, `date`, `t`).
fn time_like(name: &str) -> bool {
    let n = name.to_ascii_lowercase();
    n == "t" || ["time", "stamp", "secs", "date"].iter().any(|w| n.contains(w))
}

/// Reads `dir` as one folder per class of CSV touches.
pub fn read_folder(dir: &Path, opts: &ImportOptions) -> Result<Imported> {
    let entries = |d: &Path| -> Result<Vec<PathBuf>> {
        let mut v: Vec<PathBuf> = std::fs::read_dir(d)
            .map_err(Error::io(d))?
            .map(|e| e.map(|e| e.path()))
            .collect::<std::io::Result<_>>()
            .map_err(Error::io(d))?;
        v.sort();
        Ok(v)
    };
    let class_dirs: Vec<PathBuf> = entries(dir)?.into_iter().filter(|p| p.is_dir()).collect();
    if class_dirs.is_empty() {
        return Err(import_error(dir, None, "holds no class folder (expected one folder per class, each with one CSV file per touch)"));
    }
    let mut header: Option<(PathBuf, Vec<String>)> = None;
    let mut touches = Vec::new();
    let mut classes = Vec::new();
    for (class, class_dir) in class_dirs.iter().enumerate() {
        let files: Vec<PathBuf> =
            entries(class_dir)?.into_iter().filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("csv"))).collect();
        if files.is_empty() {
            return Err(import_error(class_dir, None, "an empty class: this folder holds no .csv file"));
        }
        if files.len() < FOLDS {
            return Err(import_error(
                class_dir,
                None,
                format!(
                    "{} touches, too few to split: each of the {FOLDS} folds (training, validation, test) needs one of every class",
                    files.len()
                ),
            ));
        }
        classes.push(class_dir.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default());
        for path in files {
            let (names, touch) = read_touch(&path, class)?;
            match &header {
                None => header = Some((path.clone(), names)),
                Some((first, h)) if *h != names => {
                    return Err(import_error(
                        &path,
                        Some(1),
                        format!("its header differs from {}'s: {:?} against {:?}", first.display(), names, h),
                    ));
                }
                Some(_) => {}
            }
            touches.push(touch);
        }
    }
    let (_, names) = header.expect("at least one touch was read");
    let (chosen, left_out) = choose_columns(&names, &touches, opts)?;
    let channels: Vec<String> = chosen.iter().map(|&c| names[c].clone()).collect();
    if let Some((h, w)) = opts.grid {
        if h * w != channels.len() {
            return Err(Error::Usage(format!(
                "--grid {h}x{w} holds {} channels, and {} columns were chosen: {channels:?}",
                h * w,
                channels.len()
            )));
        }
    }
    let mut out = Imported { touches: Vec::new(), labels: Vec::new(), classes, sources: Vec::new(), channels, left_out, grid: opts.grid };
    for t in touches {
        let mut frames = vec![Vec::with_capacity(t.rows.len()); chosen.len()];
        for (row, line) in t.rows.iter().zip(&t.lines) {
            for (k, &c) in chosen.iter().enumerate() {
                let v = row[c].ok_or_else(|| import_error(&t.path, Some(*line), format!("column `{}` is not a number here", names[c])))?;
                frames[k].push(v as f32);
            }
        }
        out.touches.push(frames);
        out.labels.push(t.class as u32);
        out.sources.push(t.path.strip_prefix(dir).unwrap_or(&t.path).display().to_string());
    }
    Ok(out)
}

/// One CSV touch: its header and rows; a ragged row is an error naming its line.
fn read_touch(path: &Path, class: usize) -> Result<(Vec<String>, Touch)> {
    let mut reader = csv::ReaderBuilder::new()
        .flexible(true)
        .trim(csv::Trim::All)
        .from_path(path)
        .map_err(|e| import_error(path, None, e.to_string()))?;
    let names: Vec<String> = reader.headers().map_err(|e| import_error(path, Some(1), e.to_string()))?.iter().map(String::from).collect();
    let (mut rows, mut lines) = (Vec::new(), Vec::new());
    for record in reader.records() {
        let record = record.map_err(|e| import_error(path, e.position().map(|p| p.line()), e.to_string()))?;
        let line = record.position().map_or(0, |p| p.line());
        if record.len() != names.len() {
            return Err(import_error(path, Some(line), format!("a ragged row: {} fields, the header has {}", record.len(), names.len())));
        }
        rows.push(record.iter().map(|cell| cell.parse::<f64>().ok().filter(|v| v.is_finite())).collect());
        lines.push(line);
    }
    if rows.is_empty() {
        return Err(import_error(path, None, "holds a header and no frame"));
    }
    Ok((names, Touch { class, path: path.to_path_buf(), rows, lines }))
}

/// The columns to import (indices into the header) and those left out, with why.
fn choose_columns(names: &[String], touches: &[Touch], opts: &ImportOptions) -> Result<(Vec<usize>, LeftOut)> {
    // The first cell of a column that is not a number, if any.
    let text_at =
        |c: usize| touches.iter().find_map(|t| t.rows.iter().zip(&t.lines).find(|(r, _)| r[c].is_none()).map(|(_, l)| (&t.path, *l)));
    if !opts.columns.is_empty() {
        let mut chosen = Vec::new();
        for pattern in &opts.columns {
            let hits: Vec<usize> = (0..names.len()).filter(|&c| matches(pattern, &names[c]) && !chosen.contains(&c)).collect();
            if hits.is_empty() {
                return Err(Error::Usage(format!("--columns {pattern}: no column of the header matches; it has {names:?}")));
            }
            chosen.extend(hits);
        }
        if let Some((c, (path, line))) = chosen.iter().find_map(|&c| text_at(c).map(|at| (c, at))) {
            return Err(import_error(path, Some(line), format!("column `{}` holds text, not a number", names[c])));
        }
        let left_out = (0..names.len()).filter(|c| !chosen.contains(c)).map(|c| (names[c].clone(), "not chosen")).collect();
        return Ok((chosen, left_out));
    }
    let (mut chosen, mut left_out) = (Vec::new(), Vec::new());
    for (c, name) in names.iter().enumerate() {
        let values = || touches.iter().flat_map(|t| t.rows.iter().map(move |r| r[c]));
        let why = if text_at(c).is_some() {
            Some("not numeric")
        } else if time_like(name) {
            Some("a time stamp by its name")
        } else if touches.iter().all(|t| t.rows.len() > 1 && t.rows.windows(2).all(|w| w[1][c] > w[0][c])) {
            Some("a time stamp: it rises in every touch")
        } else if values().all(|v| v == touches[0].rows[0][c]) {
            Some("constant")
        } else {
            None
        };
        match why {
            Some(why) => left_out.push((name.clone(), why)),
            None => chosen.push(c),
        }
    }
    if chosen.is_empty() {
        return Err(Error::Usage(format!("no column is a numeric channel that varies; the header has {names:?} (choose with --columns)")));
    }
    Ok((chosen, left_out))
}

impl Imported {
    /// Frames of the shortest and the longest touch.
    pub fn length_range(&self) -> (usize, usize) {
        let lengths = self.touches.iter().map(|t| t[0].len());
        (lengths.clone().min().unwrap_or(0), lengths.max().unwrap_or(0))
    }

    /// Touches per class, in class order.
    pub fn per_class(&self) -> Vec<usize> {
        let mut counts: BTreeMap<u32, usize> = BTreeMap::new();
        self.labels.iter().for_each(|l| *counts.entry(*l).or_default() += 1);
        (0..self.classes.len() as u32).map(|c| counts.get(&c).copied().unwrap_or(0)).collect()
    }

    /// Writes the set as `.npz`: `x` (float32, `[N, channels, T]` or `[N, rows, cols, T]`, `T`
    /// the longest touch, shorter touches zero-padded), `y`, `lengths`, and the names as UTF-8
    /// lines (`class_names`, `sources`, `channels`).
    pub fn write_npz(&self, path: &Path) -> Result<()> {
        let (_, longest) = self.length_range();
        let n = self.touches.len();
        let channels = self.channels.len();
        let mut x = vec![0f32; n * channels * longest];
        for (i, touch) in self.touches.iter().enumerate() {
            for (c, frames) in touch.iter().enumerate() {
                let at = (i * channels + c) * longest;
                x[at..at + frames.len()].copy_from_slice(frames);
            }
        }
        let shape = match self.grid {
            Some((h, w)) => vec![n, h, w, longest],
            None => vec![n, channels, longest],
        };
        let bad = |e: &dyn std::fmt::Display| Error::Usage(format!("writing {}: {e}", path.display()));
        let file = std::fs::File::create(path).map_err(Error::io(path))?;
        let mut npz = NpzWriter::new(std::io::BufWriter::new(file));
        let lines = |v: &[String]| Array1::from(v.join("\n").into_bytes());
        npz.add_array("x", &ArrayD::from_shape_vec(IxDyn(&shape), x).map_err(|e| bad(&e))?).map_err(|e| bad(&e))?;
        npz.add_array("y", &Array1::from(self.labels.iter().map(|l| *l as i64).collect::<Vec<_>>())).map_err(|e| bad(&e))?;
        npz.add_array("lengths", &Array1::from(self.touches.iter().map(|t| t[0].len() as i64).collect::<Vec<_>>())).map_err(|e| bad(&e))?;
        npz.add_array("class_names", &lines(&self.classes)).map_err(|e| bad(&e))?;
        npz.add_array("sources", &lines(&self.sources)).map_err(|e| bad(&e))?;
        npz.add_array("channels", &lines(&self.channels)).map_err(|e| bad(&e))?;
        npz.finish().map_err(|e| bad(&e))?;
        Ok(())
    }
}

#[cfg(test)]
mod tests;
