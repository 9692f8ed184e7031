//! What the runtime reports instead of crashing.

use std::panic::UnwindSafe;

/// Every way a call can fail; its message names the file, the value or the call at fault.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// Why.
        source: std::io::Error,
    },
    /// The bytes are not an ONNX model this runtime wires.
    #[error("{path} is not a readable ONNX model: {reason}")]
    NotOnnx {
        /// The file (or the name given to bytes in memory).
        path: String,
        /// What is wrong.
        reason: String,
    },
    /// The file was altered or damaged since export (its digest).
    #[error("{path} is refused: {reason}")]
    Corrupted {
        /// The file.
        path: String,
        /// How its content fails the digest.
        reason: pvt3_format::Integrity,
    },
    /// The file's metadata is not a pvt3 model's of this format.
    #[error("{path} is not a pvt3 model this runtime reads: {reason}")]
    NotPvt3 {
        /// The file.
        path: String,
        /// What is wrong with its metadata.
        reason: pvt3_format::HeaderError,
    },
    /// An input of another length than `batch` windows.
    #[error("input has {got} values; expected {expected} ({batch} × {sample})")]
    InputLength {
        /// The values given.
        got: usize,
        /// The values `batch` windows have.
        expected: usize,
        /// The windows asked for.
        batch: usize,
        /// One window's shape, in words.
        sample: String,
    },
    /// An input value that is a NaN or an infinity.
    #[error("input value {index} is {value}: only finite values can be classified")]
    NonFinite {
        /// Where it is in the input.
        index: usize,
        /// The value.
        value: f32,
    },
    /// An `.npy` file that cannot be read as windows.
    #[error("{path}: {reason}")]
    Npy {
        /// The file.
        path: String,
        /// What is wrong.
        reason: String,
    },
    /// A frame of another length than the model's.
    #[error("a frame has {got} values; expected {expected} (height × width × channels)")]
    FrameLength {
        /// The frame's values.
        got: usize,
        /// The model's frame's values.
        expected: usize,
    },
    /// A frame pushed into a session whose window is full.
    #[error("the touch already has all its {frames} frames: finish it first")]
    TooManyFrames {
        /// Frames in a window.
        frames: usize,
    },
    /// A session finished before its window was in.
    #[error("the touch has {got} of its {frames} frames: push the rest before finishing")]
    Incomplete {
        /// Frames pushed.
        got: usize,
        /// Frames in a window.
        frames: usize,
    },
    /// A peek before the first whole temporal token.
    #[error("no provisional answer yet: the touch has no whole temporal token ({tubelet} frames) so far")]
    NoTokenYet {
        /// Frames per temporal token.
        tubelet: usize,
    },
    /// A peek on a file exported before format 1.1.
    #[error("this file gives no provisional answers: it was exported before format 1.1; export it again")]
    NoPrefixes,
    /// A stream of a file whose spectral head reads the whole window.
    #[error("this model's spectral head reads the whole window (the file was exported before the head streamed; export it again): classify whole windows, not a stream")]
    WholeWindowOnly,
    /// A batch of no windows.
    #[error("batch size must be at least 1")]
    EmptyBatch,
    /// A continuous stream asked to answer every 0 tokens.
    #[error("a continuous classification answers every 1 or more temporal tokens, not every 0")]
    NoStride,
    /// A batch too large to address.
    #[error("a batch of {batch} windows has more values than memory can address")]
    BatchTooLarge {
        /// The windows asked for.
        batch: usize,
    },
    /// More than one thread, in a build without the `threads` feature.
    #[error("{asked} threads asked for, but this build runs one thread per plan (built without the `threads` feature)")]
    NoThreads {
        /// The threads asked for.
        asked: usize,
    },
    /// A touch could not be brought to how the model reads touches ([`crate::read_touch`]).
    #[error("reading the touch: {0}")]
    Touch(String),
    /// A buffer whose size the file decides could not be allocated on this machine.
    #[error("{what} needs {bytes} bytes, which this machine could not allocate")]
    OutOfMemory {
        /// The buffer.
        what: &'static str,
        /// Its size.
        bytes: usize,
    },
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

/// The runtime's results.
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
