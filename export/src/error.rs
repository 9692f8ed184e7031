//! What can keep a model from being exported.

#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("cannot export: {0}")]
    Unsupported(String),
    #[error("not a consistent baked model: {0}")]
    Inconsistent(String),
    #[error("{path}: {source}")]
    Io { path: String, source: std::io::Error },
}

pub type Result<T> = std::result::Result<T, Error>;
