//! Pictures of runs, as SVG files a browser or any viewer shows: a run's training curves
//! ([`curves::run_figure`]), a cross-validation's runs side by side ([`curves::cv_figure`]), a
//! confusion matrix ([`confusion`]) and what part of a touch gives ([`anytime`]). Written by
//! hand (a few hundred lines of SVG text) rather than through a plotting crate, which would
//! bring a font stack into the trainer.

pub mod anytime;
pub mod chart;
pub mod confusion;
pub mod curves;

use std::path::Path;

use crate::Result;

/// `text` with the characters XML reserves escaped.
pub fn escape(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// Writes `svg` to `path` whole ([`crate::atomic::file::write_file`]), so that a viewer never sees half
/// a picture.
pub fn write(path: &Path, svg: &str) -> Result<()> {
    crate::atomic::file::write_file(path, svg)
}

#[cfg(test)]
mod tests;
