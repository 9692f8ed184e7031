//! A folder of touches, as `pvt3 import` finds them: one folder per class, side by side with a
//! `--name` pattern that reads each file's class and conditions, or wherever a labels file
//! (`--labels`) lists them; each class counted against the folds. Shared by the CSV ([`super::csv`]) and the camera ([`super::camera`]) import.

use std::path::{Path, PathBuf};

use super::decode;
use super::decode::is_bag;
use super::labels::Labels;
use super::npz::check_line;
use crate::data::{Condition, FOLDS};
use crate::{Error, Result};

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
    /// A field takes the longest value that lets the rest match (`{class}_*` reads
    /// `aluminium_foil` from `aluminium_foil_3`), a `*` the shortest. In time proportional to the
    /// pattern's parts times the name's length: which parts can match which end of the name is
    /// worked out once, where trying every split took exponential time.
    pub fn read(&self, name: &str) -> Option<Vec<String>> {
        let n: Vec<char> = name.chars().collect();
        let (parts, len) = (self.parts.len(), n.len());
        // rest[i][j]: parts i.. match name[j..]; from_on[i][j]: rest[i][k] for some k ≥ j.
        let mut rest = vec![vec![false; len + 1]; parts + 1];
        let mut from_on = vec![vec![false; len + 2]; parts + 1];
        rest[parts][len] = true;
        for i in (0..=parts).rev() {
            if i < parts {
                for j in (0..=len).rev() {
                    rest[i][j] = match &self.parts[i] {
                        Part::Char(c) => j < len && n[j] == *c && rest[i + 1][j + 1],
                        Part::Any => from_on[i + 1][j],
                        Part::Field(_) => from_on[i + 1][j + 1],
                    };
                }
            }
            for j in (0..=len).rev() {
                from_on[i][j] = rest[i][j] || from_on[i][j + 1];
            }
        }
        if !rest[0][0] {
            return None;
        }
        let (mut j, mut values) = (0, Vec::new());
        for (i, part) in self.parts.iter().enumerate() {
            j = match part {
                Part::Char(_) => j + 1,
                Part::Any => (j..=len).find(|k| rest[i + 1][*k]).expect("a way on"),
                Part::Field(_) => {
                    let k = (j + 1..=len).rev().find(|k| rest[i + 1][*k]).expect("a way on");
                    values.push(n[j..k].iter().collect());
                    k
                }
            };
        }
        Some(values)
    }
}

impl std::fmt::Display for NamePattern {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.text)
    }
}

/// Where each touch's class and conditions come from.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum Naming {
    /// Its class folder's name (`DIR/<class>/<touch>`).
    #[default]
    Folders,
    /// Its file's name (`--name`): the class where the pattern has `{class}` (the touches then
    /// side by side in the folder), else its class folder's; the pattern's other fields the
    /// conditions.
    Pattern(NamePattern),
    /// A labels file (`--labels`): a row a touch, its path relative to the folder.
    Labels(Labels),
}

impl Naming {
    /// The names of the conditions each touch records.
    fn conditions(&self) -> Vec<String> {
        match self {
            Self::Folders => Vec::new(),
            Self::Pattern(p) => p.conditions().into_iter().map(String::from).collect(),
            Self::Labels(l) => l.conditions.clone(),
        }
    }
}

/// The conditions `naming` gives the touches, each touch's values in `values`.
pub(super) fn conditions(naming: &Naming, values: &[Vec<String>]) -> Vec<Condition> {
    let names = naming.conditions();
    names
        .iter()
        .enumerate()
        .map(|(k, name)| Condition { name: name.clone(), levels: values.iter().map(|v| v[k].clone()).collect() })
        .collect()
}

/// What one touch is on disk.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Recording {
    /// A CSV file: a header row, then a row a frame; or a ROS 2 bag of a taxel array.
    Csv,
    /// A camera's: a video file, a folder of frame images or a still image ([`super::camera`]).
    Camera,
}

impl Recording {
    pub(super) fn is_touch(self, path: &Path) -> bool {
        match self {
            Self::Csv => is_csv(path) || is_bag(path),
            Self::Camera => decode::is_camera_touch(path),
        }
    }

    /// What a touch is, for errors.
    fn what(self) -> &'static str {
        match self {
            Self::Csv => ".csv file or ROS 2 bag",
            Self::Camera => "video, folder of frame images, still image or ROS 2 bag",
        }
    }
}

/// A touch's file, found by [`list_touches`]: its class name, its condition values and, for a
/// touch a labels file cuts from a long recording, the seconds it takes.
pub(super) struct Listed {
    pub(super) path: PathBuf,
    pub(super) class: String,
    pub(super) values: Vec<String>,
    pub(super) window: Option<(f64, f64)>,
}

impl Listed {
    /// The touch's name in a data set: its path under `dir`, and the seconds it takes of it.
    pub(super) fn source(&self, dir: &Path) -> String {
        let path = self.path.strip_prefix(dir).unwrap_or(&self.path).display().to_string();
        match self.window {
            Some((start, end)) => format!("{path} ({start} s to {end} s)"),
            None => path,
        }
    }
}

/// The touches of `dir` and the classes, sorted: one folder per class, side by side when the
/// `--name` pattern names the class (both sorted), or as a labels file lists them (in its order).
/// Refuses a class of fewer touches than folds.
pub(super) fn list_touches(dir: &Path, naming: &Naming, kind: Recording) -> Result<(Vec<Listed>, Vec<String>)> {
    // The touches, and where a class too small is told: its folder, or the folder or labels file
    // that lists the touches side by side.
    let (files, flat_in) = match naming {
        Naming::Labels(labels) => (labelled_touches(dir, labels, kind)?, Some(labels.file.as_path())),
        Naming::Pattern(p) if p.fields().contains(&CLASS_FIELD) => (side_by_side(dir, p, kind)?, Some(dir)),
        Naming::Pattern(p) => (in_class_folders(dir, Some(p), kind)?, None),
        Naming::Folders => (in_class_folders(dir, None, kind)?, None),
    };
    for f in &files {
        storable(&f.path, f.path.strip_prefix(dir).unwrap_or(&f.path).as_os_str())?;
    }
    let classes: Vec<String> = files.iter().map(|f| f.class.clone()).collect::<std::collections::BTreeSet<_>>().into_iter().collect();
    check_enough_touches(dir, &files, &classes, flat_in)?;
    Ok((files, classes))
}

/// The touches side by side in `dir`, their class and conditions read from their names.
fn side_by_side(dir: &Path, pattern: &NamePattern, kind: Recording) -> Result<Vec<Listed>> {
    let found = touches_in(dir, kind)?;
    if found.is_empty() {
        let why = format!("holds no {} (--name {pattern} names the class, so the touches lie side by side in this folder)", kind.what());
        return Err(Error::import(dir, None, why));
    }
    let class_at = pattern.fields().iter().position(|f| *f == CLASS_FIELD).expect("the class field");
    let mut files = Vec::with_capacity(found.len());
    for path in found {
        let mut values = read_name(&path, pattern)?;
        let class = values.remove(class_at);
        files.push(Listed { path, class, values, window: None });
    }
    Ok(files)
}

/// The touches of `dir`'s class folders (a class its folder's name), their conditions read from
/// their names where a pattern is given.
fn in_class_folders(dir: &Path, name: Option<&NamePattern>, kind: Recording) -> Result<Vec<Listed>> {
    let class_dirs: Vec<PathBuf> = sorted_entries(dir)?.into_iter().filter(|p| p.is_dir()).collect();
    if class_dirs.is_empty() {
        let why = format!(
            "holds no class folder (expected one folder per class, each with one {} per touch, or --name with a {{class}} field)",
            kind.what()
        );
        return Err(Error::import(dir, None, why));
    }
    let mut files = Vec::new();
    for class_dir in class_dirs {
        let found = touches_in(&class_dir, kind)?;
        if found.is_empty() {
            return Err(Error::import(&class_dir, None, format!("an empty class: this folder holds no {}", kind.what())));
        }
        let class = storable(&class_dir, class_dir.file_name().unwrap_or_default())?;
        for path in found {
            let values = match name {
                Some(pattern) => read_name(&path, pattern)?,
                None => Vec::new(),
            };
            files.push(Listed { path, class: class.clone(), values, window: None });
        }
    }
    Ok(files)
}

/// The fields `pattern` reads from the name of the touch at `path`: a file's name without its
/// extension, a folder's whole name.
fn read_name(path: &Path, pattern: &NamePattern) -> Result<Vec<String>> {
    let stem = if path.is_dir() { path.file_name() } else { path.file_stem() };
    let stem = storable(path, stem.unwrap_or_default())?;
    pattern.read(&stem).ok_or_else(|| Error::import(path, None, format!("its name `{stem}` does not match --name {pattern}")))
}

/// `name` (of the file or folder `path`) as a data set stores its names, or why it cannot be:
/// they are UTF-8, one a line, so a name that is not UTF-8 (which a lossy reading would merge
/// with another) or holds a line break (which would split it in two) is refused.
pub(super) fn storable(path: &Path, name: &std::ffi::OsStr) -> Result<String> {
    let text = name.to_str().ok_or_else(|| Error::import(path, None, "its name is not UTF-8, as a data set's names are: rename it"))?;
    check_line(text).map_err(|why| Error::import(path, None, format!("its name {why}: rename it")))?;
    Ok(text.to_string())
}

/// The touches `labels` lists under `dir`, in its order: each must be a touch of `kind`.
fn labelled_touches(dir: &Path, labels: &Labels, kind: Recording) -> Result<Vec<Listed>> {
    let mut files = Vec::with_capacity(labels.rows.len());
    for row in &labels.rows {
        let path = dir.join(&row.path);
        if !kind.is_touch(&path) {
            return Err(Error::import(
                &labels.file,
                Some(row.line),
                format!("{} is not a {} (in {})", row.path, kind.what(), dir.display()),
            ));
        }
        if row.window.is_some() && !is_bag(&path) {
            let why = format!("{}: start and end cut touches from ROS 2 bags, and it is none", row.path);
            return Err(Error::import(&labels.file, Some(row.line), why));
        }
        files.push(Listed { path, class: row.class.clone(), values: row.values.clone(), window: row.window });
    }
    Ok(files)
}

/// The entries of folder `d`, sorted.
fn sorted_entries(d: &Path) -> Result<Vec<PathBuf>> {
    let mut v: Vec<PathBuf> =
        std::fs::read_dir(d).map_err(Error::io(d))?.map(|e| e.map(|e| e.path())).collect::<std::io::Result<_>>().map_err(Error::io(d))?;
    v.sort();
    Ok(v)
}

/// Whether `path` is a CSV file.
fn is_csv(path: &Path) -> bool {
    path.is_file() && path.extension().is_some_and(|e| e.eq_ignore_ascii_case("csv"))
}

/// Whether `dir` holds a camera's touches (videos, frame folders, still images, or bags whose
/// `topic` is a camera's), side by side or one folder per class, or as a labels file lists
/// them, and no CSV file: what `pvt3 import` reads it as. Bags of a taxel array's topic are read
/// as CSV touches are.
pub fn holds_camera_touches(dir: &Path, naming: &Naming, topic: Option<&str>) -> bool {
    let touches: Vec<PathBuf> = match naming {
        Naming::Labels(labels) => labels.rows.iter().map(|r| dir.join(&r.path)).collect(),
        _ => {
            let entries = sorted_entries(dir).unwrap_or_default();
            let within = entries.iter().filter(|p| p.is_dir()).flat_map(|d| sorted_entries(d).unwrap_or_default());
            entries.iter().cloned().chain(within).collect()
        }
    };
    let camera = match naming {
        Naming::Labels(_) => touches.iter().all(|p| Recording::Camera.is_touch(p)),
        _ => touches.iter().any(|p| Recording::Camera.is_touch(p)) && !touches.iter().any(|p| is_csv(p)),
    };
    camera && touches.iter().find(|p| is_bag(p)).is_none_or(|bag| decode::bag_holds_camera(bag, topic))
}

/// The touches of kind `kind` in folder `d`, sorted.
fn touches_in(d: &Path, kind: Recording) -> Result<Vec<PathBuf>> {
    Ok(sorted_entries(d)?.into_iter().filter(|p| kind.is_touch(p)).collect())
}

/// Refuses a class with fewer touches than folds, naming its folder in `dir`, or `flat_in`: the
/// folder or labels file that lists the touches side by side.
fn check_enough_touches(dir: &Path, files: &[Listed], classes: &[String], flat_in: Option<&Path>) -> Result<()> {
    for class in classes {
        let count = files.iter().filter(|f| f.class == *class).count();
        if count < FOLDS {
            let too_few = format!(
                "{count} touches, too few to split: each of the {FOLDS} folds (training, validation, test) needs one of every class"
            );
            return Err(match flat_in {
                Some(place) => Error::import(place, None, format!("class `{class}`: {too_few}")),
                None => Error::import(&dir.join(class), None, too_few),
            });
        }
    }
    Ok(())
}

/// Touches per class of `classes`, in class order, of touches labelled `labels`.
pub(super) fn per_class(labels: &[u32], classes: usize) -> Vec<usize> {
    let mut counts = vec![0; classes];
    labels.iter().for_each(|l| counts[*l as usize] += 1);
    counts
}
