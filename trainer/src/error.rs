//! The trainer library's errors. Each names the file and what was expected of it.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    Spec(#[from] pvt3_spec::Error),
    #[error(transparent)]
    Model(#[from] pvt3_models::Error),
    #[error(transparent)]
    Candle(#[from] candle_core::Error),
    #[error("data set {path}: {reason}")]
    Data { path: PathBuf, reason: String },
    #[error("checkpoint {path}: {reason}")]
    Checkpoint { path: PathBuf, reason: String },
    #[error("{path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    #[error(transparent)]
    Export(#[from] pvt3_export::Error),
    #[error(transparent)]
    Runtime(#[from] pvt3_runtime::Error),
    #[error("{0}")]
    Usage(String),
}

pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// An import's error at `path` (and `line`, where one is known), naming them.
    pub fn import(path: &std::path::Path, line: Option<u64>, reason: impl Into<String>) -> Error {
        let place = match line {
            Some(l) => format!("{}:{l}", path.display()),
            None => path.display().to_string(),
        };
        Error::Usage(format!("{place}: {}", reason.into()))
    }

    /// A data set's error: the file `path` and what is wrong with it.
    pub fn data(path: &std::path::Path, reason: impl Into<String>) -> Error {
        Error::Data { path: path.to_path_buf(), reason: reason.into() }
    }

    pub fn io(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> Error + '_ {
        move |source| Error::Io { path: path.to_path_buf(), source }
    }
}
