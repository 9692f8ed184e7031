//! The errors of the model crate: configuration, input shape and checkpoint problems, each saying
//! what was expected.

/// Everything that can go wrong while building, loading or running a model.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    Candle(#[from] candle_core::Error),
    #[error("invalid model configuration: {0}")]
    Config(String),
    #[error("unknown preset `{0}`; the presets are {presets}, each also as vit-NAME and raec-NAME", presets = crate::config::PRESETS.join(", "))]
    UnknownPreset(String),
    #[error("input has shape {got:?}, but the model expects [batch, {expected}]")]
    InputShape { got: Vec<usize>, expected: String },
    #[error("weights file {path}: {reason}")]
    Weights { path: String, reason: String },
}

pub type Result<T> = std::result::Result<T, Error>;
