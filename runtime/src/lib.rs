//! The robot side of pvt3: load one exported `.onnx` and classify tactile windows with tract.
//! Depends on tract alone (no candle, no trainer), so a robot links only what it runs.
//!
//! The file says what it expects: class names, the input layout and the kept frames are read
//! from its metadata. Inputs are validated before they reach tract: a wrong length or a NaN or
//! infinite value is a typed [`Error`], never a panic. Each batch size gets its own optimised plan
//! with a fixed input shape (a fixed shape ran markedly faster than a symbolic batch in tract).

mod classifier;
mod cut;
mod error;
pub mod ffi;
mod kernels;
mod npy;
mod plan;
mod small_products;
mod stream;

pub use classifier::{Classifier, Prediction};
pub use error::{Error, Result};
pub use kernels::tune as tune_kernels;
pub use npy::read_npy;
pub use stream::Session;
