//! The errors of the plain model: configuration, input shape and tensor problems, each saying
//! what was expected.

/// Everything that can go wrong while describing, pruning, baking or running the plain model.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("invalid model configuration: {0}")]
    Config(String),
    #[error("unknown preset `{0}`; the presets are {presets}, each also as vit-NAME and raec-NAME", presets = crate::config::PRESETS.join(", "))]
    UnknownPreset(String),
    #[error("input has shape {got:?}, but the model expects [batch, {expected}]")]
    InputShape { got: Vec<usize>, expected: String },
    /// A tensor that `task` (bake, prune, …) needs is not among the named tensors.
    #[error("cannot {task}: tensor `{name}` is missing")]
    MissingTensor { task: &'static str, name: String },
    #[error("cannot {task}: `{name}` has shape {got:?}, expected {expected:?}")]
    TensorShape { task: &'static str, name: String, got: Vec<usize>, expected: Vec<usize> },
    #[error("weights file {path}: {reason}")]
    Weights { path: String, reason: String },
}

pub type Result<T> = std::result::Result<T, Error>;
