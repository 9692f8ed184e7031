//! What every imported set writes beside its frames ([`crate::data::key`]): the labels, the
//! class names, each touch's file and conditions, the kind of sensor, names as UTF-8 lines and
//! records as JSON.

use std::path::Path;

use ndarray::Array1;
use ndarray_npy::NpzWriter;

use crate::data::{key, Condition};
use crate::Error;

/// Refuses a name that holds a line break: a data set keeps its names one a line.
pub(super) fn check_line(name: &str) -> std::result::Result<(), String> {
    match name.contains(['\n', '\r']) {
        true => Err(format!("{name:?} holds a line break, and a data set keeps its names one a line")),
        false => Ok(()),
    }
}

/// A data set being written ([`write`]).
pub(super) type Npz = NpzWriter<std::io::BufWriter<std::fs::File>>;

/// What every imported set records beside its frames: the labels `y`, the class names, each
/// touch's file and its conditions ([`key`]).
pub(super) struct Records<'a> {
    pub(super) labels: &'a [u32],
    pub(super) classes: &'a [String],
    pub(super) sources: &'a [String],
    pub(super) conditions: &'a [Condition],
    /// The kind of sensor the frames came from.
    pub(super) sensor: pvt3_spec::Sensor,
}

/// Writes a data set to `path`: `fill` adds its frames and what else it holds, then come the
/// `records` every set holds ([`super::csv::Imported::write_npz`],
/// [`super::camera::CameraSet::write_npz`]). An error names the file.
pub(super) fn write(
    path: &Path,
    records: Records,
    fill: impl FnOnce(&mut Npz) -> Result<(), Box<dyn std::error::Error>>,
) -> crate::Result<()> {
    let file = std::fs::File::create(path).map_err(Error::io(path))?;
    let mut npz = NpzWriter::new(std::io::BufWriter::new(file));
    let written = fill(&mut npz).and_then(|()| Ok(add_records(&mut npz, records)?)).and_then(|()| Ok(npz.finish().map(drop)?));
    written.map_err(|e| Error::Usage(format!("writing {}: {e}", path.display())))
}

/// The lines of `v` as one UTF-8 array, as the data set holds names ([`key`]).
pub(super) fn lines(v: &[String]) -> Array1<u8> {
    Array1::from(v.join("\n").into_bytes())
}

/// `value` as one line of JSON, UTF-8 bytes under `name` (what [`crate::data::Dataset::load`]
/// reads as a line).
pub(super) fn add_json(npz: &mut Npz, name: &str, value: &impl serde::Serialize) -> std::result::Result<(), ndarray_npy::WriteNpzError> {
    let text = serde_json::to_string(value).expect("plain data serialises");
    npz.add_array(name, &Array1::from(text.into_bytes()))
}

/// Adds `records` ([`Records`]) to `npz`.
fn add_records(
    npz: &mut Npz,
    Records { labels, classes, sources, conditions, sensor }: Records,
) -> std::result::Result<(), ndarray_npy::WriteNpzError> {
    npz.add_array(key::SENSOR, &lines(&[sensor.name().to_string()]))?;
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
