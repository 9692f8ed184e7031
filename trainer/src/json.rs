//! JSON files as a run keeps them: written whole, or atomically where another process may read
//! or write the same file; read with an error that names the file; a figure that was not
//! measured written as `null` and read back as NaN. Below everything that stores its records
//! this way (checkpoints, provenance, metrics, results, a head's choice).

use std::path::Path;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::{Error, Result};

pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    std::fs::write(path, text(value)).map_err(Error::io(path))
}

/// A record as a run's JSON files hold it: indented, a newline at the end.
fn text<T: Serialize>(value: &T) -> String {
    serde_json::to_string_pretty(value).expect("plain data serialises") + "\n"
}

/// Writes JSON whole ([`crate::atomic::file::write_file`]), where another process may read or write the
/// same file.
pub fn write_json_atomically<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    crate::atomic::file::write_file(path, text(value))
}

pub fn read_json<T: DeserializeOwned>(path: &Path) -> Result<T> {
    let text = std::fs::read_to_string(path).map_err(Error::io(path))?;
    serde_json::from_str(&text).map_err(|e| Error::Checkpoint { path: path.to_path_buf(), reason: format!("malformed JSON ({e})") })
}

/// Reads a number, or `null` as NaN: how JSON writes a figure that was not measured (a final
/// model's validation accuracy, a run's test accuracy without test touches).
pub fn nan_from_null<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}
