//! What the runtime reports instead of crashing.

use std::panic::UnwindSafe;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("{path}: {source}")]
    Io { path: String, source: std::io::Error },
    #[error("{path} is not a readable ONNX model: {reason}")]
    NotOnnx { path: String, reason: String },
    #[error("{path} is refused: {reason}")]
    Corrupted { path: String, reason: pvt3_format::Integrity },
    #[error("{path} is not a pvt3 model this runtime reads: {reason}")]
    NotPvt3 { path: String, reason: pvt3_format::HeaderError },
    #[error("input has {got} values; expected {expected} ({batch} × {sample})")]
    InputLength { got: usize, expected: usize, batch: usize, sample: String },
    #[error("input value {index} is {value}: only finite values can be classified")]
    NonFinite { index: usize, value: f32 },
    #[error("{path}: {reason}")]
    Npy { path: String, reason: String },
    #[error("a frame has {got} values; expected {expected} (height × width × channels)")]
    FrameLength { got: usize, expected: usize },
    #[error("the touch already has all its {frames} frames: finish it first")]
    TooManyFrames { frames: usize },
    #[error("the touch has {got} of its {frames} frames: push the rest before finishing")]
    Incomplete { got: usize, frames: usize },
    #[error("no provisional answer yet: the touch has no whole temporal token ({tubelet} frames) so far")]
    NoTokenYet { tubelet: usize },
    #[error("this file gives no provisional answers: it was exported before format 1.1; export it again")]
    NoPrefixes,
    #[error("this model's spectral head reads the whole window (the file was exported before the head streamed; export it again): classify whole windows, not a stream")]
    WholeWindowOnly,
    #[error("batch size must be at least 1")]
    EmptyBatch,
    #[error("a continuous classification answers every 1 or more temporal tokens, not every 0")]
    NoStride,
    #[error("a batch of {batch} windows has more values than memory can address")]
    BatchTooLarge { batch: usize },
    #[error("{asked} threads asked for, but this build runs one thread per plan (built without the `threads` feature)")]
    NoThreads { asked: usize },
    /// A touch could not be brought to how the model reads touches ([`crate::read_touch`]).
    #[error("reading the touch: {0}")]
    Touch(String),
    /// tract failed (or panicked, caught) on a file that passed every check.
    #[error("tract: {0}")]
    Tract(String),
}

/// A touch the file's reading cannot read, as the runtime reports it.
impl From<pvt3_format::ReadError> for Error {
    fn from(e: pvt3_format::ReadError) -> Self {
        match e {
            pvt3_format::ReadError::Touch(reason) => Self::Touch(reason),
            pvt3_format::ReadError::NonFinite { index, value } => Self::NonFinite { index, value },
            pvt3_format::ReadError::FrameLength { got, expected } => Self::FrameLength { got, expected },
        }
    }
}

pub type Result<T> = std::result::Result<T, Error>;

pub(crate) fn tract_error(e: impl std::fmt::Display) -> Error {
    Error::Tract(e.to_string())
}

/// Runs `f`, turning a panic into [`Error::Tract`] with its message. tract can panic on a graph
/// it did not expect; a file that passed the integrity check was written by the exporter, but
/// no panic may reach a caller of the library either way.
pub(crate) fn catch_panic<T>(f: impl FnOnce() -> T + UnwindSafe) -> Result<T> {
    std::panic::catch_unwind(f).map_err(|panic| {
        let what = panic.downcast_ref::<&str>().map(|s| s.to_string()).or_else(|| panic.downcast_ref::<String>().cloned());
        Error::Tract(format!("panicked: {}", what.unwrap_or_else(|| "(no message)".into())))
    })
}
