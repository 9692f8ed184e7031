//! `pvt3 import`: a folder of CSV recordings, or of a camera's videos or frame folders
//! ([`camera`]), → a data set (`.npz`) the trainer reads.
//!
//! The folder holds one folder per class (its name is the class's), each with one CSV file per
//! touch: a header row, then one row per frame. Or, with a file name pattern that names the
//! class (`{class}_F{force}_V{speed}_*`), the CSV files side by side in one folder. Which columns
//! are sensor channels is chosen by name or pattern, or by default every numeric column that
//! varies, time-stamp-like columns left out (and said so). Touches may differ in length; the set
//! records each touch's (`lengths`), its file (`sources`), the class names (`class_names`) and
//! the conditions the pattern reads from the names (speed, force, …), see [`crate::data::key`].

use std::path::{Path, PathBuf};

use ndarray::{Array1, ArrayD, IxDyn};
use ndarray_npy::NpzWriter;

use pvt3_runtime::{read_touch, Reading, Touch};

use crate::data::{key, Condition, FOLDS};
use crate::{Error, Result};

pub mod camera;
mod decode;

/// What to import and how.
#[derive(Clone, Debug, Default)]
pub struct ImportOptions {
    /// Column names or patterns (`*` any run of characters, `?` one), in the order given; empty:
    /// every numeric column that varies, time-stamp-like ones left out.
    pub columns: Vec<String>,
    /// The sensor's grid, rows × columns of the chosen channels (row-major); `None`: one column of
    /// channels (`[N, channels, frames]`, read as a channels × 1 grid).
    pub grid: Option<(usize, usize)>,
    /// What each file's name says: its class and the conditions of the touch.
    pub name: Option<NamePattern>,
    /// Each touch read by distance travelled rather than by time: the condition that holds its
    /// sliding speed, and the speed every touch is resampled to (a touch of `n` frames at speed
    /// `v` becomes `n · |v| / speed` frames, [`pvt3_runtime::read_touch`]), so that a texture's ridges lie
    /// as many frames apart at every speed.
    pub per_distance: Option<(String, f64)>,
    /// Each touch's readings scaled to one pressing force: the condition that holds its force,
    /// and the force every touch is scaled to (readings times `force / f`, for a touch pressed
    /// at `f`): a capacitive sensor's readings grow about in proportion to the force.
    pub per_force: Option<(String, f64)>,
}

/// A file name pattern (the name without its extension, or a folder's name): `{field}` reads the
/// longest non-empty run of characters that lets the rest match as that field's value, `*`
/// matches any run, every other character itself. The field `class` names the touch's class; every other field is a condition of the touch (a speed, a force, a
/// direction) that `pvt3 cv --hold-out` can hold out.
#[derive(Clone, Debug, PartialEq)]
pub struct NamePattern {
    text: String,
    parts: Vec<Part>,
}

#[derive(Clone, Debug, PartialEq)]
enum Part {
    Char(char),
    Any,
    Field(String),
}

/// The field of a [`NamePattern`] that names the class.
pub const CLASS_FIELD: &str = "class";

impl std::str::FromStr for NamePattern {
    type Err = String;

    fn from_str(text: &str) -> std::result::Result<Self, String> {
        let mut parts = Vec::new();
        let mut chars = text.chars();
        while let Some(c) = chars.next() {
            parts.push(match c {
                '*' => Part::Any,
                '{' => {
                    let mut field = String::new();
                    let closed = chars.by_ref().any(|c| {
                        c == '}' || {
                            field.push(c);
                            false
                        }
                    });
                    if !closed || field.is_empty() || !field.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
                        return Err(format!("`{text}`: `{{{field}` is not a field; write {{name}} with letters, digits or _"));
                    }
                    if parts.iter().any(|p| *p == Part::Field(field.clone())) {
                        return Err(format!("`{text}`: the field {{{field}}} appears twice"));
                    }
                    Part::Field(field)
                }
                '}' => return Err(format!("`{text}`: a `}}` without its `{{`")),
                c => Part::Char(c),
            });
        }
        if parts.windows(2).any(|w| !matches!(w[0], Part::Char(_)) && !matches!(w[1], Part::Char(_))) {
            return Err(format!("`{text}`: two fields or wildcards side by side cannot be told apart; put a separator between them"));
        }
        Ok(Self { text: text.to_string(), parts })
    }
}

impl NamePattern {
    /// The fields, in the pattern's order.
    pub fn fields(&self) -> Vec<&str> {
        self.parts.iter().filter_map(|p| if let Part::Field(f) = p { Some(f.as_str()) } else { None }).collect()
    }

    /// The conditions: every field but the class.
    pub fn conditions(&self) -> Vec<&str> {
        self.fields().into_iter().filter(|f| *f != CLASS_FIELD).collect()
    }

    /// Each field's value in `name`, in the pattern's order, or `None` where it does not match.
    pub fn read(&self, name: &str) -> Option<Vec<String>> {
        fn go(parts: &[Part], name: &[char], values: &mut Vec<String>) -> bool {
            match parts.split_first() {
                None => name.is_empty(),
                Some((Part::Char(c), rest)) => name.first() == Some(c) && go(rest, &name[1..], values),
                Some((Part::Any, rest)) => (0..=name.len()).any(|k| go(rest, &name[k..], values)),
                // The longest value that lets the rest match: `{class}_*` reads `aluminium_foil`
                // from `aluminium_foil_3`.
                Some((Part::Field(_), rest)) => (1..=name.len()).rev().any(|k| {
                    values.push(name[..k].iter().collect());
                    go(rest, &name[k..], values) || {
                        values.pop();
                        false
                    }
                }),
            }
        }
        let mut values = Vec::new();
        go(&self.parts, &name.chars().collect::<Vec<_>>(), &mut values).then_some(values)
    }
}

impl std::fmt::Display for NamePattern {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.text)
    }
}

/// One touch as its file holds it: its class, its file, its frames `[frames][columns]` (every column of the
/// header; non-numeric cells are `None`).
struct TouchFile {
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
    /// The conditions the file name pattern read, each with its value for every touch.
    pub conditions: Vec<Condition>,
    /// How the touches were read, if they were brought to one speed or force.
    pub reading: Option<Reading>,
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
    let (files, classes) = list_touches(dir, opts.name.as_ref(), Recording::Csv)?;
    let (names, touches, condition_values) = read_touches(files, &classes)?;
    let conditions = conditions(opts.name.as_ref(), &condition_values);
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
    let reading = (opts.per_distance.is_some() || opts.per_force.is_some())
        .then(|| Reading { speed: opts.per_distance.as_ref().map(|p| p.1), force: opts.per_force.as_ref().map(|p| p.1) });
    if let Some(problem) = reading.and_then(|r| r.problem()) {
        return Err(Error::Usage(format!("--per-distance/--per-force: {problem}")));
    }
    let speeds = known_values("--per-distance", &opts.per_distance, &conditions, &touches)?;
    let forces = known_values("--per-force", &opts.per_force, &conditions, &touches)?;
    let mut out = Imported {
        touches: Vec::new(),
        labels: Vec::new(),
        classes,
        sources: Vec::new(),
        channels,
        left_out,
        grid: opts.grid,
        conditions,
        reading,
    };
    for (n, t) in touches.into_iter().enumerate() {
        let touch = Touch { speed: speeds[n], force: forces[n] };
        out.touches.push(chosen_frames(&t, (&chosen, &names), reading.as_ref().map(|r| (r, touch)))?);
        out.labels.push(t.class as u32);
        out.sources.push(t.path.strip_prefix(dir).unwrap_or(&t.path).display().to_string());
    }
    Ok(out)
}

/// The conditions `pattern` reads from the touches' names, each touch's values in `values`.
fn conditions(pattern: Option<&NamePattern>, values: &[Vec<String>]) -> Vec<Condition> {
    let names = pattern.map(NamePattern::conditions).unwrap_or_default();
    names
        .iter()
        .enumerate()
        .map(|(k, name)| Condition { name: name.to_string(), levels: values.iter().map(|v| v[k].clone()).collect() })
        .collect()
}

/// What one touch is on disk.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Recording {
    /// A CSV file: a header row, then a row a frame.
    Csv,
    /// A camera's: a video file, or a folder of frame images ([`camera`]).
    Camera,
}

impl Recording {
    fn is_touch(self, path: &Path) -> bool {
        match self {
            Self::Csv => path.is_file() && path.extension().is_some_and(|e| e.eq_ignore_ascii_case("csv")),
            Self::Camera => decode::is_camera_touch(path),
        }
    }

    /// What a touch is, for errors.
    fn what(self) -> &'static str {
        match self {
            Self::Csv => ".csv file",
            Self::Camera => "video or folder of frame images",
        }
    }
}

/// A touch's file, found by [`list_touches`]: its class name and its condition values.
struct Listed {
    path: PathBuf,
    class: String,
    values: Vec<String>,
}

/// The touches of `dir`, sorted, and the classes, sorted: one folder per class, or side by side
/// when the `--name` pattern names the class. Refuses a class of fewer touches than folds.
fn list_touches(dir: &Path, name: Option<&NamePattern>, kind: Recording) -> Result<(Vec<Listed>, Vec<String>)> {
    let mut files = Vec::new();
    let read_name = |path: &Path, pattern: &NamePattern| -> Result<Vec<String>> {
        // A file's name without its extension; a folder's whole name.
        let stem = if path.is_dir() { path.file_name() } else { path.file_stem() };
        let stem = stem.map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        pattern.read(&stem).ok_or_else(|| import_error(path, None, format!("its name `{stem}` does not match --name {pattern}")))
    };
    // Whether the names give the class, the touches then side by side in `dir`.
    let flat = name.is_some_and(|p| p.fields().contains(&CLASS_FIELD));
    match name {
        Some(pattern) if flat => {
            let found = touches_in(dir, kind)?;
            if found.is_empty() {
                return Err(import_error(
                    dir,
                    None,
                    format!("holds no {} (--name {pattern} names the class, so the touches lie side by side in this folder)", kind.what()),
                ));
            }
            for path in found {
                let mut values = read_name(&path, pattern)?;
                let class = values.remove(pattern.fields().iter().position(|f| *f == CLASS_FIELD).expect("the class field"));
                files.push(Listed { path, class, values });
            }
        }
        _ => {
            let class_dirs: Vec<PathBuf> = sorted_entries(dir)?.into_iter().filter(|p| p.is_dir()).collect();
            if class_dirs.is_empty() {
                return Err(import_error(
                    dir,
                    None,
                    format!(
                        "holds no class folder (expected one folder per class, each with one {} per touch, or --name with a {{class}} field)",
                        kind.what()
                    ),
                ));
            }
            for class_dir in class_dirs {
                let found = touches_in(&class_dir, kind)?;
                if found.is_empty() {
                    return Err(import_error(&class_dir, None, format!("an empty class: this folder holds no {}", kind.what())));
                }
                let class = class_dir.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
                for path in found {
                    let values = match name {
                        Some(pattern) => read_name(&path, pattern)?,
                        None => Vec::new(),
                    };
                    files.push(Listed { path, class: class.clone(), values });
                }
            }
        }
    }
    let classes: Vec<String> = files.iter().map(|f| f.class.clone()).collect::<std::collections::BTreeSet<_>>().into_iter().collect();
    check_enough_touches(dir, &files, &classes, flat)?;
    Ok((files, classes))
}

/// The entries of folder `d`, sorted.
fn sorted_entries(d: &Path) -> Result<Vec<PathBuf>> {
    let mut v: Vec<PathBuf> =
        std::fs::read_dir(d).map_err(Error::io(d))?.map(|e| e.map(|e| e.path())).collect::<std::io::Result<_>>().map_err(Error::io(d))?;
    v.sort();
    Ok(v)
}

/// Whether `dir` holds a camera's touches (videos or frame folders), side by side or one folder
/// per class, and no CSV file: what `pvt3 import` reads it as.
pub fn holds_camera_touches(dir: &Path) -> bool {
    let entries = sorted_entries(dir).unwrap_or_default();
    let holds = |kind: Recording| {
        entries.iter().any(|p| kind.is_touch(p))
            || entries.iter().filter(|p| p.is_dir()).any(|d| touches_in(d, kind).is_ok_and(|t| !t.is_empty()))
    };
    holds(Recording::Camera) && !holds(Recording::Csv)
}

/// The touches of kind `kind` in folder `d`, sorted.
fn touches_in(d: &Path, kind: Recording) -> Result<Vec<PathBuf>> {
    Ok(sorted_entries(d)?.into_iter().filter(|p| kind.is_touch(p)).collect())
}

/// Refuses a class with fewer touches than folds, naming its folder (or `dir`, when `flat`).
fn check_enough_touches(dir: &Path, files: &[Listed], classes: &[String], flat: bool) -> Result<()> {
    for class in classes {
        let count = files.iter().filter(|f| f.class == *class).count();
        if count < FOLDS {
            let too_few = format!(
                "{count} touches, too few to split: each of the {FOLDS} folds (training, validation, test) needs one of every class"
            );
            return Err(if flat {
                import_error(dir, None, format!("class `{class}`: {too_few}"))
            } else {
                import_error(&dir.join(class), None, too_few)
            });
        }
    }
    Ok(())
}

/// Every listed touch read, in order: the columns' names (one header for all), the touches and
/// their condition values.
fn read_touches(files: Vec<Listed>, classes: &[String]) -> Result<(Vec<String>, Vec<TouchFile>, Vec<Vec<String>>)> {
    let mut header: Option<(PathBuf, Vec<String>)> = None;
    let mut touches = Vec::new();
    let mut condition_values = Vec::new();
    for Listed { path, class, values } in files {
        let (names, touch) = read_file(&path, classes.binary_search(&class).expect("a known class"))?;
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
        condition_values.push(values);
    }
    let (_, names) = header.expect("at least one touch was read");
    Ok((names, touches, condition_values))
}

/// Each touch's value of the condition `given` names (`option` its flag), as a number: what the
/// robot would know of the touch. `None` for every touch when no condition is given.
fn known_values(option: &str, given: &Option<(String, f64)>, conditions: &[Condition], touches: &[TouchFile]) -> Result<Vec<Option<f64>>> {
    let Some((name, _)) = given else { return Ok(vec![None; touches.len()]) };
    let condition = conditions.iter().find(|c| c.name == *name).ok_or_else(|| {
        let known: Vec<&String> = conditions.iter().map(|c| &c.name).collect();
        Error::Usage(format!("{option} {name}: no such condition; --name records {known:?}"))
    })?;
    condition
        .levels
        .iter()
        .zip(touches)
        .map(|(v, t)| {
            v.parse::<f64>()
                .map(Some)
                .map_err(|_| import_error(&t.path, None, format!("{option} {name}: its {name} `{v}` is not a number")))
        })
        .collect()
}

/// A touch's chosen columns (`chosen` of the columns `names`) as channels of frames; with a
/// reading, read as the robot will read its touches (the runtime's own function).
fn chosen_frames(t: &TouchFile, (chosen, names): (&[usize], &[String]), reading: Option<(&Reading, Touch)>) -> Result<Vec<Vec<f32>>> {
    let mut frames = vec![Vec::with_capacity(t.rows.len()); chosen.len()];
    for (row, line) in t.rows.iter().zip(&t.lines) {
        for (k, &c) in chosen.iter().enumerate() {
            let v = row[c].ok_or_else(|| import_error(&t.path, Some(*line), format!("column `{}` is not a number here", names[c])))?;
            frames[k].push(v as f32);
        }
    }
    if let Some((reading, touch)) = reading {
        let read = read_touch(&frames.concat(), frames.len(), reading, touch).map_err(|e| import_error(&t.path, None, e.to_string()))?;
        let len = read.len() / frames.len();
        frames = read.chunks(len).map(<[f32]>::to_vec).collect();
    }
    Ok(frames)
}

/// One CSV touch: its header and rows; a ragged row is an error naming its line.
fn read_file(path: &Path, class: usize) -> Result<(Vec<String>, TouchFile)> {
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
    Ok((names, TouchFile { class, path: path.to_path_buf(), rows, lines }))
}

/// The columns to import (indices into the header) and those left out, with why.
fn choose_columns(names: &[String], touches: &[TouchFile], opts: &ImportOptions) -> Result<(Vec<usize>, LeftOut)> {
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
        // Every column is left out, in the header's order.
        let why: Vec<String> = (0..)
            .zip(&left_out)
            .map(|(c, (name, why))| match text_at(c) {
                Some((path, line)) => format!("`{name}` {why} ({}:{line})", path.display()),
                None => format!("`{name}` {why}"),
            })
            .collect();
        return Err(Error::Usage(format!("no column is a numeric channel that varies: {} (choose with --columns)", why.join(", "))));
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
        per_class(&self.labels, self.classes.len())
    }

    /// Writes the set as `.npz`: `x` (float32, `[N, channels, T]` or `[N, rows, cols, T]`, `T`
    /// the longest touch, shorter touches zero-padded), `y`, `lengths`, and the names as UTF-8
    /// lines (`class_names`, `sources`, `channels`, the conditions: [`key`]).
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
        npz.add_array(key::X, &ArrayD::from_shape_vec(IxDyn(&shape), x).map_err(|e| bad(&e))?).map_err(|e| bad(&e))?;
        npz.add_array(key::LENGTHS, &Array1::from(self.touches.iter().map(|t| t[0].len() as i64).collect::<Vec<_>>()))
            .map_err(|e| bad(&e))?;
        npz.add_array(key::CHANNELS, &lines(&self.channels)).map_err(|e| bad(&e))?;
        if let Some(reading) = &self.reading {
            add_json(&mut npz, key::READING, reading).map_err(|e| bad(&e))?;
        }
        add_records(&mut npz, &self.labels, &self.classes, &self.sources, &self.conditions).map_err(|e| bad(&e))?;
        npz.finish().map_err(|e| bad(&e))?;
        Ok(())
    }
}

/// Touches per class of `classes`, in class order, of touches labelled `labels`.
fn per_class(labels: &[u32], classes: usize) -> Vec<usize> {
    let mut counts = vec![0; classes];
    labels.iter().for_each(|l| counts[*l as usize] += 1);
    counts
}

/// A data set being written ([`Imported::write_npz`], [`camera::CameraSet::write_npz`]).
type Npz = NpzWriter<std::io::BufWriter<std::fs::File>>;

/// The lines of `v` as one UTF-8 array, as the data set holds names ([`key`]).
fn lines(v: &[String]) -> Array1<u8> {
    Array1::from(v.join("\n").into_bytes())
}

/// What every imported set records beside its frames: the labels `y`, the class names, each
/// touch's file and its conditions ([`key`]).
/// `value` as one line of JSON, UTF-8 bytes under `name` (what [`crate::data::Dataset::load`]
/// reads as a line).
fn add_json(npz: &mut Npz, name: &str, value: &impl serde::Serialize) -> std::result::Result<(), ndarray_npy::WriteNpzError> {
    let text = serde_json::to_string(value).expect("plain data serialises");
    npz.add_array(name, &Array1::from(text.into_bytes()))
}

fn add_records(
    npz: &mut Npz,
    labels: &[u32],
    classes: &[String],
    sources: &[String],
    conditions: &[Condition],
) -> std::result::Result<(), ndarray_npy::WriteNpzError> {
    npz.add_array(key::Y, &Array1::from(labels.iter().map(|l| *l as i64).collect::<Vec<_>>()))?;
    npz.add_array(key::CLASS_NAMES, &lines(classes))?;
    npz.add_array(key::SOURCES, &lines(sources))?;
    if !conditions.is_empty() {
        let names: Vec<String> = conditions.iter().map(|c| c.name.clone()).collect();
        npz.add_array(key::CONDITIONS, &lines(&names))?;
        for c in conditions {
            npz.add_array(key::condition(&c.name).as_str(), &lines(&c.levels))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests;
