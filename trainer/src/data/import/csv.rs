//! A folder of CSV touches → a data set: one CSV file a touch, a header row, then one row per
//! frame; or one ROS 2 bag a touch, a taxel array's messages its frames ([`bag_rows`]). Which
//! columns are sensor channels is chosen by name or pattern, or by default every numeric column
//! that varies, time-stamp-like columns left out (and said so), and every value of a bag's
//! message. Touches may differ in length; with `--per-distance` or `--per-force` each is read as
//! the robot will read its touches (the runtime's `read_touch`).

use std::path::{Path, PathBuf};

use ndarray::{Array1, ArrayD, IxDyn};

use pvt3_format::{read_touch, Reading, Touch};

use super::folder::{conditions, list_touches, per_class, Listed, Naming, Recording};
use super::npz::{self, add_json, lines, Records};
use super::timing::Timing;
use crate::data::{key, Condition};
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
    /// Where each touch's class and conditions come from.
    pub naming: Naming,
    /// Each touch read by distance travelled rather than by time: the condition that holds its
    /// sliding speed, and the speed every touch is resampled to (a touch of `n` frames at speed
    /// `v` becomes `n · |v| / speed` frames, [`pvt3_format::read_touch`]), so that a texture's ridges lie
    /// as many frames apart at every speed.
    pub per_distance: Option<(String, f64)>,
    /// Each touch's readings scaled to one pressing force: the condition that holds its force,
    /// and the force every touch is scaled to (readings times `force / f`, for a touch pressed
    /// at `f`): a capacitive sensor's readings grow about in proportion to the force.
    pub per_force: Option<(String, f64)>,
    /// The topic a bag's frames are read from (a `std_msgs/msg/*MultiArray`).
    pub topic: Option<String>,
    /// The kind of sensor the set records; `None`: a tactile array's, what a CSV file or a
    /// multi-array holds (`--sensor camera` for a camera's frames exported as columns).
    pub sensor: Option<pvt3_spec::Sensor>,
}

/// One touch as its file holds it: its class, its file, its frames `[frames][columns]` (every column of the
/// header; non-numeric cells are `None`).
struct TouchFile {
    class: usize,
    path: PathBuf,
    /// Its name in the data set ([`Listed::source`]).
    source: String,
    rows: Vec<Vec<Option<f64>>>,
    /// The file line of each row, for errors (a bag's rows: the touch's message index, never
    /// told: a message's values are checked as it is decoded).
    lines: Vec<u64>,
    /// A bag's: how its frames' times strayed.
    timing: Option<Timing>,
}

/// What every touch of a set must share: its columns' names and, for a bag's touches, their
/// messages' layout (`layout.dim`'s sizes; a CSV file has none).
#[derive(Clone, Debug, PartialEq)]
struct Header {
    names: Vec<String>,
    layout: Option<Vec<usize>>,
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
    /// The touches whose frames' times were not evenly spaced and rising (bags), by source.
    pub timings: Vec<(String, Timing)>,
    /// A bag's messages' layout (`layout.dim`'s sizes, outermost first).
    pub layout: Option<Vec<usize>>,
    /// The kind of sensor the set records ([`ImportOptions::sensor`]).
    pub sensor: pvt3_spec::Sensor,
}

/// Names listed, a long list elided in its middle: `p0, p1, …, p10, …, p1023 (1024 names)`.
pub fn elided(names: &[String]) -> String {
    const SHOWN: usize = 12;
    match names.len() > SHOWN {
        true => format!("{}, …, {} ({} names)", names[..SHOWN - 1].join(", "), names[names.len() - 1], names.len()),
        false => names.join(", "),
    }
}

/// Columns left out of an import, each with why.
pub type LeftOut = Vec<(String, &'static str)>;

/// Whether `name` matches `pattern` (`*`: any run of characters, `?`: one). Greedy, going back
/// only to the last `*`: at most the name's length times the pattern's steps, where trying every
/// split at every `*` took exponential time (`*a*a*a*a*b` against a long name ran for minutes).
pub fn matches(pattern: &str, name: &str) -> bool {
    let (p, n): (Vec<char>, Vec<char>) = (pattern.chars().collect(), name.chars().collect());
    let (mut i, mut j) = (0, 0);
    // The pattern just after the last `*` seen, and where in the name that `*`'s run now ends.
    let mut star: Option<(usize, usize)> = None;
    while j < n.len() {
        if i < p.len() && (p[i] == '?' || (p[i] != '*' && p[i] == n[j])) {
            (i, j) = (i + 1, j + 1);
        } else if i < p.len() && p[i] == '*' {
            star = Some((i + 1, j));
            i += 1;
        } else if let Some((after, end)) = star {
            // The last `*` takes one character more.
            star = Some((after, end + 1));
            (i, j) = (after, end + 1);
        } else {
            return false;
        }
    }
    p[i..].iter().all(|c| *c == '*')
}

/// A column whose name says it is a time (`time`, `stamp`, `secs`, `date`, `t`).
fn time_like(name: &str) -> bool {
    let n = name.to_ascii_lowercase();
    n == "t" || ["time", "stamp", "secs", "date"].iter().any(|w| n.contains(w))
}

/// Reads `dir` as one folder per class of CSV touches.
pub fn read_folder(dir: &Path, opts: &ImportOptions) -> Result<Imported> {
    let (files, classes) = list_touches(dir, &opts.naming, Recording::Csv)?;
    let ReadTouches { header, touches, condition_values } = read_touches(dir, files, &classes, opts.topic.as_deref())?;
    let names = header.names;
    let conditions = conditions(&opts.naming, &condition_values);
    let every_value = header.layout.is_some();
    let (chosen, left_out) = choose_columns(&names, &touches, opts, every_value)?;
    let channels: Vec<String> = chosen.iter().map(|&c| names[c].clone()).collect();
    let grid = grid(opts.grid, header.layout.as_deref(), chosen.len() == names.len(), &channels)?;
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
        grid,
        conditions,
        reading,
        timings: Vec::new(),
        layout: header.layout,
        sensor: opts.sensor.unwrap_or(pvt3_spec::Sensor::Array),
    };
    for (n, t) in touches.into_iter().enumerate() {
        let touch = Touch { speed: speeds[n], force: forces[n] };
        out.touches.push(chosen_frames(&t, (&chosen, &names), reading.as_ref().map(|r| (r, touch)))?);
        out.labels.push(t.class as u32);
        if let Some(timing) = t.timing.filter(Timing::strays) {
            out.timings.push((t.source.clone(), timing));
        }
        out.sources.push(t.source);
    }
    Ok(out)
}

/// The channels' grid: `--grid`, or a bag's layout of two dimensions where every value of its
/// messages is a channel (`all_chosen`); a `--grid` that disagrees with that layout, or that
/// holds another number of channels than `channels`, is refused.
fn grid(given: Option<(usize, usize)>, layout: Option<&[usize]>, all_chosen: bool, channels: &[String]) -> Result<Option<(usize, usize)>> {
    let layout = match layout {
        Some(&[h, w]) if all_chosen => Some((h, w)),
        _ => None,
    };
    if let (Some((h, w)), Some((rows, cols))) = (given, layout.filter(|l| Some(*l) != given)) {
        return Err(Error::Usage(format!("--grid {h}x{w} disagrees with the bag's messages, laid out {rows} × {cols} (layout.dim)")));
    }
    let grid = given.or(layout);
    if let Some((h, w)) = grid.filter(|(h, w)| h * w != channels.len()) {
        let (held, chosen) = (h * w, channels.len());
        return Err(Error::Usage(format!("--grid {h}x{w} holds {held} channels, and {chosen} columns were chosen: {}", elided(channels))));
    }
    Ok(grid)
}

/// Every listed touch, read in order.
struct ReadTouches {
    /// One header for all.
    header: Header,
    touches: Vec<TouchFile>,
    /// Each touch's condition values.
    condition_values: Vec<Vec<String>>,
}

fn read_touches(dir: &Path, files: Vec<Listed>, classes: &[String], topic: Option<&str>) -> Result<ReadTouches> {
    let mut header: Option<(PathBuf, Header)> = None;
    let mut touches = Vec::new();
    let mut condition_values = Vec::new();
    for listed in files {
        let class = classes.binary_search(&listed.class).expect("a known class");
        let (names, touch) = read_listed(dir, &listed, class, topic)?;
        let path = &listed.path;
        match &header {
            None => header = Some((path.clone(), names)),
            Some((first, h)) if *h != names => {
                let why = match (&names.layout, &h.layout) {
                    (Some(layout), Some(was)) => format!(
                        "its messages' layout {layout:?} of {} values differs from {}'s: {was:?} of {}",
                        names.names.len(),
                        first.display(),
                        h.names.len()
                    ),
                    (None, None) => format!("its header differs from {}'s: {:?} against {:?}", first.display(), names.names, h.names),
                    _ => format!("a bag and a CSV file ({}) in one set: their channels cannot be matched", first.display()),
                };
                return Err(Error::import(path, names.layout.is_none().then_some(1), why));
            }
            Some(_) => {}
        }
        touches.push(touch);
        condition_values.push(listed.values);
    }
    let (_, header) = header.expect("at least one touch was read");
    Ok(ReadTouches { header, touches, condition_values })
}

/// The listed touch: a CSV file, or a bag's messages.
fn read_listed(dir: &Path, listed: &Listed, class: usize, topic: Option<&str>) -> Result<(Header, TouchFile)> {
    #[cfg(feature = "bags")]
    if super::decode::is_bag(&listed.path) {
        return read_bag(dir, listed, class, topic);
    }
    let _ = topic;
    let (names, touch) = read_file(&listed.path, class, listed.source(dir))?;
    Ok((Header { names, layout: None }, touch))
}

/// A bag's touch as a CSV touch: a row a message, a column a value.
#[cfg(feature = "bags")]
fn read_bag(dir: &Path, listed: &Listed, class: usize, topic: Option<&str>) -> Result<(Header, TouchFile)> {
    let bag = bag_rows::read(&listed.path, listed.window, topic).map_err(|e| Error::import(&listed.path, None, e))?;
    let names = (0..bag.rows[0].len()).map(bag_rows::channel).collect();
    let rows = bag.rows.iter().map(|r| r.iter().map(|v| Some(f64::from(*v))).collect()).collect();
    let touch = TouchFile {
        class,
        path: listed.path.clone(),
        source: listed.source(dir),
        rows,
        lines: (0..bag.rows.len() as u64).collect(),
        timing: Some(bag.timing),
    };
    Ok((Header { names, layout: Some(bag.dims) }, touch))
}

/// Each touch's value of the condition `given` names (`option` its flag), as a number: what the
/// robot would know of the touch. `None` for every touch when no condition is given.
fn known_values(option: &str, given: &Option<(String, f64)>, conditions: &[Condition], touches: &[TouchFile]) -> Result<Vec<Option<f64>>> {
    let Some((name, _)) = given else { return Ok(vec![None; touches.len()]) };
    let condition = conditions.iter().find(|c| c.name == *name).ok_or_else(|| {
        let known: Vec<&String> = conditions.iter().map(|c| &c.name).collect();
        Error::Usage(format!("{option} {name}: no such condition; the names (--name) or labels (--labels) record {known:?}"))
    })?;
    condition
        .levels
        .iter()
        .zip(touches)
        .map(|(v, t)| {
            v.parse::<f64>()
                .map(Some)
                .map_err(|_| Error::import(&t.path, None, format!("{option} {name}: its {name} `{v}` is not a number")))
        })
        .collect()
}

/// A touch's chosen columns (`chosen` of the columns `names`) as channels of frames; with a
/// reading, read as the robot will read its touches (the runtime's own function).
fn chosen_frames(t: &TouchFile, (chosen, names): (&[usize], &[String]), reading: Option<(&Reading, Touch)>) -> Result<Vec<Vec<f32>>> {
    let mut frames = vec![Vec::with_capacity(t.rows.len()); chosen.len()];
    for (row, line) in t.rows.iter().zip(&t.lines) {
        for (k, &c) in chosen.iter().enumerate() {
            let v = row[c].ok_or_else(|| Error::import(&t.path, Some(*line), format!("column `{}` is not a number here", names[c])))?;
            // A data set holds 32-bit floats: a reading beyond their range would be stored as ±inf.
            if !(v as f32).is_finite() {
                let why = format!("column `{}` holds {v:e}, beyond the range of the 32-bit floats a data set holds (±3.4e38)", names[c]);
                return Err(Error::import(&t.path, Some(*line), why));
            }
            frames[k].push(v as f32);
        }
    }
    if let Some((reading, touch)) = reading {
        let read = read_touch(&frames.concat(), frames.len(), reading, touch).map_err(|e| Error::import(&t.path, None, e.to_string()))?;
        if read.iter().any(|v| !v.is_finite()) {
            return Err(Error::import(
                &t.path,
                None,
                "its readings scaled to the --per-force force pass the range of 32-bit floats (±3.4e38)",
            ));
        }
        let len = read.len() / frames.len();
        frames = read.chunks(len).map(<[f32]>::to_vec).collect();
    }
    Ok(frames)
}

/// One CSV touch, named `source` in the data set: its header and rows; a ragged row is an error naming its line.
fn read_file(path: &Path, class: usize, source: String) -> Result<(Vec<String>, TouchFile)> {
    let mut reader = ::csv::ReaderBuilder::new()
        .flexible(true)
        .trim(::csv::Trim::All)
        .from_path(path)
        .map_err(|e| Error::import(path, None, e.to_string()))?;
    let names: Vec<String> = reader.headers().map_err(|e| Error::import(path, Some(1), e.to_string()))?.iter().map(String::from).collect();
    let (mut rows, mut lines) = (Vec::new(), Vec::new());
    for record in reader.records() {
        let record = record.map_err(|e| Error::import(path, e.position().map(|p| p.line()), e.to_string()))?;
        let line = record.position().map_or(0, |p| p.line());
        if record.len() != names.len() {
            return Err(Error::import(path, Some(line), format!("a ragged row: {} fields, the header has {}", record.len(), names.len())));
        }
        rows.push(record.iter().map(|cell| cell.parse::<f64>().ok().filter(|v| v.is_finite())).collect());
        lines.push(line);
    }
    if rows.is_empty() {
        return Err(Error::import(path, None, "holds a header and no frame"));
    }
    Ok((names, TouchFile { class, path: path.to_path_buf(), source, rows, lines, timing: None }))
}

/// The columns to import (indices into the header) and those left out, with why; by default,
/// with `every_value` (a bag's touches, whose messages hold the sensor's values and no time),
/// every column.
fn choose_columns(names: &[String], touches: &[TouchFile], opts: &ImportOptions, every_value: bool) -> Result<(Vec<usize>, LeftOut)> {
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
            return Err(Error::import(path, Some(line), format!("column `{}` holds text, not a number", names[c])));
        }
        let left_out = (0..names.len()).filter(|c| !chosen.contains(c)).map(|c| (names[c].clone(), "not chosen")).collect();
        return Ok((chosen, left_out));
    }
    if every_value {
        return Ok(((0..names.len()).collect(), Vec::new()));
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
        let (labels, classes, sources, conditions) = (&self.labels, &self.classes, &self.sources, &self.conditions);
        let records = Records { labels, classes, sources, conditions, sensor: self.sensor };
        npz::write(path, records, |npz| {
            npz.add_array(key::X, &ArrayD::from_shape_vec(IxDyn(&shape), x)?)?;
            npz.add_array(key::LENGTHS, &Array1::from(self.touches.iter().map(|t| t[0].len() as i64).collect::<Vec<_>>()))?;
            npz.add_array(key::CHANNELS, &lines(&self.channels))?;
            if let Some(reading) = &self.reading {
                add_json(npz, key::READING, reading)?;
            }
            Ok(())
        })
    }
}

#[cfg(feature = "bags")]
mod bag_rows;
#[cfg(test)]
mod tests;
