//! Named tensors, the plain form of a model's variables (shape and row-major values), and reading
//! them from a safetensors checkpoint: what baking, pruning and the reference start from.

use std::collections::HashMap;
use std::path::Path;

use safetensors::SafeTensors;

use crate::{Error, Result};

/// Named tensors: shape and row-major values, as read from a checkpoint.
pub type Tensors = HashMap<String, (Vec<usize>, Vec<f32>)>;

/// The error for the weights file at `path`.
pub fn weights_error(path: &Path, reason: impl Into<String>) -> Error {
    Error::Weights { path: path.display().to_string(), reason: reason.into() }
}

/// Every f32 tensor of a safetensors file as plain named tensors.
pub fn read_tensors(path: &Path) -> Result<Tensors> {
    let bytes = std::fs::read(path).map_err(|e| weights_error(path, e.to_string()))?;
    let file = SafeTensors::deserialize(&bytes).map_err(|e| weights_error(path, format!("not a valid safetensors file ({e})")))?;
    file.tensors()
        .into_iter()
        .map(|(name, view)| {
            if view.dtype() != safetensors::Dtype::F32 {
                return Err(weights_error(path, format!("tensor `{name}` is {:?}, expected F32", view.dtype())));
            }
            let values = view.data().chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect();
            Ok((name, (view.shape().to_vec(), values)))
        })
        .collect()
}
