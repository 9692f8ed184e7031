//! A labels file (`pvt3 import --labels FILE.csv`): each touch's class and conditions from a
//! table rather than from folder or file names, as public sets often keep them (a `slip.txt`
//! beside the videos, a sheet of objects). Its header names `path` (a touch's path relative to
//! the folder imported) and `class`; with `start` and `end` too, each row is the part of a long
//! recording (a ROS 2 bag) between those seconds from its first message, and one recording may
//! give several touches. Every other column is a condition of the touch, recorded for
//! `--hold-out`. A row a touch; each refusal names the file and the line.

use std::path::{Path, PathBuf};

use super::npz::check_line;
use crate::{Error, Result};

/// The columns a labels file must have.
pub const PATH_COLUMN: &str = "path";
pub const CLASS_COLUMN: &str = "class";
/// The columns that cut a touch out of a long recording, in seconds from its first message.
pub const START_COLUMN: &str = "start";
pub const END_COLUMN: &str = "end";

/// A labels file, read.
#[derive(Clone, Debug, PartialEq)]
pub struct Labels {
    /// The file, for errors.
    pub file: PathBuf,
    /// The condition columns, in the header's order.
    pub conditions: Vec<String>,
    pub rows: Vec<Row>,
}

/// One touch's row.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// The file's line, for errors.
    pub line: u64,
    /// Relative to the folder imported.
    pub path: String,
    pub class: String,
    /// One a condition, in [`Labels::conditions`]' order.
    pub values: Vec<String>,
    /// The seconds of the recording it takes, from its first message, where the file has
    /// `start` and `end`.
    pub window: Option<(f64, f64)>,
}

impl Labels {
    /// Reads `file`, refusing a header without `path` and `class`, a ragged row, an empty path
    /// or class, a path named twice, and a file without rows.
    pub fn read(file: &Path) -> Result<Self> {
        let at = |line: Option<u64>, reason: String| Error::import(file, line, reason);
        let mut reader =
            ::csv::ReaderBuilder::new().flexible(true).trim(::csv::Trim::All).from_path(file).map_err(|e| at(None, e.to_string()))?;
        let header: Vec<String> = reader.headers().map_err(|e| at(Some(1), e.to_string()))?.iter().map(String::from).collect();
        let column = |name: &str| header.iter().position(|h| h.eq_ignore_ascii_case(name));
        let (Some(path), Some(class)) = (column(PATH_COLUMN), column(CLASS_COLUMN)) else {
            return Err(at(Some(1), format!("its header {header:?} lacks `{PATH_COLUMN}` or `{CLASS_COLUMN}` (a labels file's columns: path, class, then any conditions)")));
        };
        let window = match (column(START_COLUMN), column(END_COLUMN)) {
            (Some(start), Some(end)) => Some((start, end)),
            (None, None) => None,
            _ => {
                return Err(at(
                    Some(1),
                    format!("its header has one of `{START_COLUMN}` and `{END_COLUMN}`: a touch cut from a recording needs both"),
                ))
            }
        };
        let cut = |c: &usize| window.is_some_and(|(s, e)| *c == s || *c == e);
        let others: Vec<usize> = (0..header.len()).filter(|c| *c != path && *c != class && !cut(c)).collect();
        let mut rows: Vec<Row> = Vec::new();
        for record in reader.records() {
            let record = record.map_err(|e| at(e.position().map(|p| p.line()), e.to_string()))?;
            let line = record.position().map_or(0, |p| p.line());
            if record.len() != header.len() {
                return Err(at(Some(line), format!("a ragged row: {} fields, the header has {}", record.len(), header.len())));
            }
            let row = Row {
                line,
                path: record[path].to_string(),
                class: record[class].to_string(),
                values: others.iter().map(|c| record[*c].to_string()).collect(),
                window: window.map(|(s, e)| seconds(&record[s], &record[e])).transpose().map_err(|why| at(Some(line), why))?,
            };
            if row.path.is_empty() || row.class.is_empty() {
                return Err(at(Some(line), "an empty path or class".into()));
            }
            if let Some(why) = std::iter::once(&row.path).chain([&row.class]).chain(&row.values).find_map(|v| check_line(v).err()) {
                return Err(at(Some(line), why));
            }
            if let Some(first) = rows.iter().find(|r| r.path == row.path && r.window == row.window) {
                return Err(at(Some(line), format!("{} is labelled twice (line {} too)", row.path, first.line)));
            }
            rows.push(row);
        }
        if rows.is_empty() {
            return Err(at(None, "a header and no touch".into()));
        }
        Ok(Self { file: file.to_path_buf(), conditions: others.iter().map(|c| header[*c].clone()).collect(), rows })
    }
}

/// A row's `start` and `end`: seconds, finite, from 0 on, the end after the start.
fn seconds(start: &str, end: &str) -> std::result::Result<(f64, f64), String> {
    let parse = |v: &str| v.parse::<f64>().ok().filter(|s| s.is_finite() && *s >= 0.0);
    match (parse(start), parse(end)) {
        (Some(s), Some(e)) if e > s => Ok((s, e)),
        _ => Err(format!("start `{start}` and end `{end}` are not seconds from 0 on, the end after the start")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn labels(tag: &str, text: &str) -> Result<Labels> {
        let file = std::env::temp_dir().join(format!("pvt3-labels-{tag}-{}.csv", std::process::id()));
        std::fs::write(&file, text).unwrap();
        let read = Labels::read(&file);
        std::fs::remove_file(file).unwrap();
        read
    }

    #[test]
    fn a_labels_file_gives_each_touch_its_class_and_conditions() {
        let l = labels("ok", "path,slip,class\na/x.avi,1,mug\nb/y.avi,0, cup \n").unwrap();
        assert_eq!(l.conditions, ["slip"]);
        assert_eq!(l.rows[1], Row { line: 3, path: "b/y.avi".into(), class: "cup".into(), values: vec!["0".into()], window: None });
    }

    #[test]
    fn start_and_end_cut_several_touches_from_one_recording() {
        let l = labels(
            "cut",
            "path,class,start,end,force
run.mcap,felt,0,1.5,2
run.mcap,wood,2.5,4,2
",
        )
        .unwrap();
        assert_eq!(l.conditions, ["force"]);
        assert_eq!((l.rows[0].window, l.rows[1].window), (Some((0.0, 1.5)), Some((2.5, 4.0))));
        let cases = [
            (
                "one",
                "path,class,start
a,b,1
",
                ":1: its header has one of `start` and `end`",
            ),
            (
                "backwards",
                "path,class,start,end
a,b,2,1
",
                ":2: start `2` and end `1` are not seconds",
            ),
            (
                "nan",
                "path,class,start,end
a,b,nan,1
",
                ":2: start `nan`",
            ),
            (
                "twice",
                "path,class,start,end
a,b,0,1
a,c,0,1
",
                ":3: a is labelled twice (line 2 too)",
            ),
        ];
        for (tag, text, expected) in cases {
            let msg = labels(tag, text).unwrap_err().to_string();
            assert!(msg.contains(expected), "{tag}: {msg}");
        }
    }

    #[test]
    fn a_bad_labels_file_is_refused_naming_its_line() {
        let cases = [
            ("header", "file,label\na,b\n", ":1: its header"),
            ("ragged", "path,class\na,b\nc\n", ":3: a ragged row"),
            ("empty", "path,class\na,\n", ":2: an empty path or class"),
            ("twice", "path,class\na,b\nc,d\na,e\n", ":4: a is labelled twice (line 2 too)"),
            ("none", "path,class\n", "a header and no touch"),
        ];
        for (tag, text, expected) in cases {
            let msg = labels(tag, text).unwrap_err().to_string();
            assert!(msg.contains(expected), "{tag}: {msg}");
        }
    }
}
