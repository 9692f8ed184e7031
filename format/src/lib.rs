//! The contract between `pvt3 export` and the robot runtime: what an exported `.onnx` file is
//! called inside (tensor names, metadata keys) and how it proves it is the file that was written
//! (the integrity digest), which format version it is and what its metadata says ([`Header`]).
//! Both sides read these from here and nowhere else; the runtime depends on this crate and tract
//! alone.
//!
//! What the file's reading metadata means is here too, as code both sides run: how a camera's
//! frames become the model's ([`Camera`], [`Picture::read_as`], and which frames of a recording a
//! touch takes, [`span`]) and how a touch is read by distance or at one force ([`read_touch`],
//! [`TouchReader`], [`resample`]). `pvt3 import` reads its touches with it, and a robot's
//! runtime reads its own alike.

#![warn(missing_docs)]

mod camera;
mod digest;
mod header;
pub mod onnx;
mod picture;
pub mod resample;
mod sizes;
pub mod span;
mod touch;

pub use camera::{Camera, Crop};
pub use digest::{digest, verify, Integrity};
pub use header::{answers_agree, top_class, Dims, Header, HeaderError, Reading, StopRule, FORMAT_VERSION};
pub use picture::Picture;
pub use sizes::{check_sizes, Budget, SizeError, LEAST_FILE_BYTES, VALUES_PER_BYTE};
pub use touch::{read_touch, ReadError, Touch, TouchReader};

/// Input: raw sensor frames `[batch, height, width, (channels,) frames]`.
pub const INPUT: &str = "frames";
/// Output: logits `[batch, classes]`.
pub const LOGITS: &str = "logits";
/// Output: class probabilities `[batch, classes]`.
pub const PROBABILITIES: &str = "probabilities";
/// Seam of the spatial stage: the raw frames of each kept temporal token, `[tokens, tubelet, height, width, channels]`.
pub const TOKEN_FRAMES: &str = "token_frames";
/// Seam of the spatial stage: each token's place among the kept tokens, int64 `[tokens]`.
pub const TOKEN_INDEX: &str = "token_index";
/// Seam between the stages: the spatial encoding of each kept token, `[tokens, dim]`.
pub const TOKEN_ENCODINGS: &str = "token_encodings";
/// Seam of the temporal stage (format 1.1): what every temporal attention score adds by its key,
/// `[1, 1, 1, time tokens + 1]` (the CLS token first). Zeros in the file; a runtime that puts −∞
/// on the tokens a touch has not reached yet classifies the touch so far (a provisional answer).
pub const TOKEN_BIAS: &str = "token_bias";
/// The logits of a spectral head (a model with `spectral_bands`), `[batch, classes]`, added to
/// the transformer's. They read the window itself (`INPUT`), not the tokens' encodings.
pub const SPECTRAL_LOGITS: &str = "spectral_logits";
/// The spectral head's weight of each frame, `[frames]`, computed from [`TOKEN_BIAS`]: 1 for a
/// frame of a kept temporal token received so far, 0 otherwise. A file with a spectral head and
/// this tensor streams: its temporal stage also reads the window so far (`INPUT`, anything where
/// the weight is 0). A spectral file without it (written before it existed) reads the whole
/// window, and a runtime classifies it whole only.
pub const FRAME_WEIGHTS: &str = "frame_weights";
/// Seam of a spectral head over an image's space (`spectral_space`; format 1.1, optional): every
/// frame of the windows as a row, raw, `[batch · frames, height, width, channels]`.
pub const HEAD_FRAMES: &str = "head_frames";
/// Seam of a spectral head over an image's space (format 1.1, optional): each frame's features
/// alone, before the frames are weighed, `[batch · frames, channels, features of a channel]`,
/// computed from [`HEAD_FRAMES`] row by row. A streaming runtime computes a frame's row as it
/// arrives and feeds the temporal stage the rows so far (zeros elsewhere) instead of the window.
pub const HEAD_FEATURES: &str = "head_features";

/// Metadata keys (`metadata_props` of the ONNX model).
pub mod keys {
    /// The file format's version, `major.minor` ([`crate::FORMAT_VERSION`]).
    pub const FORMAT: &str = "pvt3.format";
    /// The class names, a JSON array of strings.
    pub const CLASSES: &str = "pvt3.classes";
    /// The input layout, in words.
    pub const INPUT_LAYOUT: &str = "pvt3.input_layout";
    /// The input's units, in words.
    pub const INPUT_UNITS: &str = "pvt3.input_units";
    /// The frames of a window the model reads, a JSON array of indices.
    pub const KEPT_FRAMES: &str = "pvt3.kept_frames";
    /// The model's configuration, a JSON object.
    pub const CONFIG: &str = "pvt3.config";
    /// Where the model came from, a JSON object.
    pub const PROVENANCE: &str = "pvt3.provenance";
    /// The stopping rule of provisional answers (format 1.1, optional), a JSON
    /// [`crate::StopRule`]: `{"top_probability": 0.93, "agreeing": 3}`. The trainer calibrates
    /// it on the validation fold.
    pub const STOP_RULE: &str = "pvt3.stop_rule";
    /// How the model reads a touch (optional), a JSON [`crate::Reading`]: `{"speed": 150.0,
    /// "force": 150.0}` for a model trained on touches resampled to 150 mm/s and scaled to a
    /// force of 150. Absent: the model reads frames as the sensor records them. A runtime that
    /// does not know it classifies frames already read so alike.
    pub const READING: &str = "pvt3.reading";
    /// How a camera's frames become the model's (optional), a JSON [`crate::Camera`]:
    /// `{"recorded": [240, 320, 3], "size": [30, 40], "grey": false, "subtract_first": true}`.
    /// Absent: the model's frames are given as it reads them.
    pub const CAMERA: &str = "pvt3.camera";
    /// The integrity digest: `sha256:` and the hex SHA-256 of everything else in the file
    /// ([`crate::digest`]).
    pub const DIGEST: &str = "pvt3.digest";
}
