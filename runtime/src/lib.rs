//! The robot side of pvt3: load one exported `.onnx` and classify tactile windows with tract.
//! Depends on tract and the file contract (`pvt3-format`) alone: no candle, no trainer, so a robot
//! links only what it runs.
//!
//! The file says what it expects: class names, the input layout and the kept frames are read
//! from its metadata, whose format version must be this runtime's ([`pvt3_format::Header`]). The
//! graph is read here too: the few ONNX messages the exporter writes are decoded with prost, and
//! tract-core's operators are wired from its node types directly (`wire.rs`), without tract's
//! ONNX loader and its registry of every operator, which was most of the library's size. Inputs are validated before they reach tract: a wrong length or a NaN or
//! infinite value is a typed [`Error`], never a panic. Each batch size gets its own optimised plan
//! with a fixed input shape (a fixed shape ran markedly faster than a symbolic batch in tract).
//!
//! A file is checked before it is parsed: the exporter writes a digest of everything in it, and a
//! file altered or damaged since is refused ([`Error::Corrupted`]). Kernels are chosen by a fixed
//! rule by default ([`Kernels`]), so the same file on the same machine gives the same outputs, bit
//! for bit, at every load. No panic reaches the caller: tract's are caught as [`Error::Tract`].

#![deny(clippy::undocumented_unsafe_blocks)]
#![warn(missing_docs)]

mod classifier;
mod continuous;
mod error;
pub mod ffi;
mod fusions;
mod heap;
mod kernels;
mod npy;
mod onnx;
mod plan;
mod real_dft;
#[cfg(not(feature = "spectral"))]
mod small_fft;
mod stages;
mod stream;
mod wire;

pub use classifier::{Classifier, Prediction};
pub use continuous::Continuous;
pub use error::{Error, Result};
pub use heap::keep_freed_memory;
pub use kernels::{tune as tune_kernels, Kernels};
pub use npy::read_npy;
pub use plan::declutter;
/// How the robot's recordings become the model's frames: the file's contract, run here as the
/// training's import ran it (a camera's pictures, a touch by distance or at one force).
pub use pvt3_format::{read_touch, Camera, Crop, Picture, Reading, StopRule, Touch, TouchReader};
pub use stream::{Peek, Session};

/// The library's version and the file format it reads, e.g. `0.1.0 (format 1.1)`: what
/// `pvt3_version()` and `pvt3-run --version` say.
pub fn version() -> String {
    let (major, minor) = pvt3_format::FORMAT_VERSION;
    format!("{} (format {major}.{minor})", env!("CARGO_PKG_VERSION"))
}
