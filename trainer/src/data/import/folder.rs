//! A folder of touches, as `pvt3 import` finds them: one folder per class, or side by side with
//! a `--name` pattern that reads each file's class and conditions; each class counted against
//! the folds. Shared by the CSV ([`super::csv`]) and the camera ([`super::camera`]) import.

use std::path::{Path, PathBuf};

use super::decode;
use crate::data::{Condition, FOLDS};
use crate::{Error, Result};

/// An import's error at `path` (and `line`, where one is known), naming them.
pub(super) fn import_error(path: &Path, line: Option<u64>, reason: impl Into<String>) -> Error {
    let place = match line {
        Some(l) => format!("{}:{l}", path.display()),
        None => path.display().to_string(),
    };
    Error::Usage(format!("{place}: {}", reason.into()))
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

/// The conditions `pattern` reads from the touches' names, each touch's values in `values`.
pub(super) fn conditions(pattern: Option<&NamePattern>, values: &[Vec<String>]) -> Vec<Condition> {
    let names = pattern.map(NamePattern::conditions).unwrap_or_default();
    names
        .iter()
        .enumerate()
        .map(|(k, name)| Condition { name: name.to_string(), levels: values.iter().map(|v| v[k].clone()).collect() })
        .collect()
}

/// What one touch is on disk.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Recording {
    /// A CSV file: a header row, then a row a frame.
    Csv,
    /// A camera's: a video file, or a folder of frame images ([`super::camera`]).
    Camera,
}

impl Recording {
    pub(super) fn is_touch(self, path: &Path) -> bool {
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
pub(super) struct Listed {
    pub(super) path: PathBuf,
    pub(super) class: String,
    pub(super) values: Vec<String>,
}

/// The touches of `dir`, sorted, and the classes, sorted: one folder per class, or side by side
/// when the `--name` pattern names the class. Refuses a class of fewer touches than folds.
pub(super) fn list_touches(dir: &Path, name: Option<&NamePattern>, kind: Recording) -> Result<(Vec<Listed>, Vec<String>)> {
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

/// Touches per class of `classes`, in class order, of touches labelled `labels`.
pub(super) fn per_class(labels: &[u32], classes: usize) -> Vec<usize> {
    let mut counts = vec![0; classes];
    labels.iter().for_each(|l| counts[*l as usize] += 1);
    counts
}
