//! The errors of the model crate: candle's, and those of the plain model (configuration, input
//! shape, tensors), each saying what was expected.

/// Everything that can go wrong while building, loading or running a model.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    Candle(#[from] candle_core::Error),
    #[error(transparent)]
    Spec(#[from] pvt3_spec::Error),
}

pub type Result<T> = std::result::Result<T, Error>;
