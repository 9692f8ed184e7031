//! What the runtime reports instead of crashing.

#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("{path}: {source}")]
    Io { path: String, source: std::io::Error },
    #[error("{path} is not a readable ONNX model: {reason}")]
    NotOnnx { path: String, reason: String },
    #[error("{path} is refused: {reason}")]
    Corrupted { path: String, reason: pvt3_format::Integrity },
    #[error("{path} is not a pvt3 model: metadata `{key}` {problem}")]
    NotPvt3 { path: String, key: &'static str, problem: String },
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
    #[error("batch size must be at least 1")]
    EmptyBatch,
    /// tract failed (or panicked, caught) on a file that passed every check.
    #[error("tract: {0}")]
    Tract(String),
}

pub type Result<T> = std::result::Result<T, Error>;
