//! What every imported set writes beside its frames ([`crate::data::key`]): the labels, the
//! class names, each touch's file and conditions, names as UTF-8 lines and records as JSON.

use ndarray::Array1;
use ndarray_npy::NpzWriter;

use crate::data::{key, Condition};

/// Refuses a name that holds a line break: a data set keeps its names one a line.
pub(super) fn check_line(name: &str) -> std::result::Result<(), String> {
    match name.contains(['\n', '\r']) {
        true => Err(format!("{name:?} holds a line break, and a data set keeps its names one a line")),
        false => Ok(()),
    }
}

/// A data set being written ([`super::csv::Imported::write_npz`], [`super::camera::CameraSet::write_npz`]).
pub(super) type Npz = NpzWriter<std::io::BufWriter<std::fs::File>>;

/// The lines of `v` as one UTF-8 array, as the data set holds names ([`key`]).
pub(super) fn lines(v: &[String]) -> Array1<u8> {
    Array1::from(v.join("\n").into_bytes())
}

/// What every imported set records beside its frames: the labels `y`, the class names, each
/// touch's file and its conditions ([`key`]).
/// `value` as one line of JSON, UTF-8 bytes under `name` (what [`crate::data::Dataset::load`]
/// reads as a line).
pub(super) fn add_json(npz: &mut Npz, name: &str, value: &impl serde::Serialize) -> std::result::Result<(), ndarray_npy::WriteNpzError> {
    let text = serde_json::to_string(value).expect("plain data serialises");
    npz.add_array(name, &Array1::from(text.into_bytes()))
}

pub(super) fn add_records(
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
