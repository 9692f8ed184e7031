//! Loading and saving model weights as safetensors under the golden names. Loading checks every
//! name and shape first and says which tensor does not fit; saving writes a temporary file and
//! renames it, so an existing file is never left half-written.

use std::path::Path;

use candle_core::{DType, Device, Tensor};
use candle_nn::VarMap;
use safetensors::SafeTensors;

use crate::{Error, Result};

fn weights_error(path: &Path, reason: impl Into<String>) -> Error {
    Error::Weights { path: path.display().to_string(), reason: reason.into() }
}

/// Sets every variable of `varmap` from the safetensors file at `path`.
pub fn load_weights(varmap: &VarMap, path: &Path) -> Result<()> {
    let bytes = std::fs::read(path).map_err(|e| weights_error(path, e.to_string()))?;
    let file = SafeTensors::deserialize(&bytes)
        .map_err(|e| weights_error(path, format!("not a valid safetensors file ({e})")))?;
    let vars = varmap.data().lock().expect("varmap lock poisoned");
    let mut names: Vec<&String> = vars.keys().collect();
    names.sort();
    for name in names {
        let var = &vars[name];
        let view = file
            .tensor(name)
            .map_err(|_| weights_error(path, format!("tensor `{name}` is missing (a checkpoint of another model?)")))?;
        if view.shape() != var.dims() {
            return Err(weights_error(
                path,
                format!("tensor `{name}` has shape {:?}, the configuration expects {:?}", view.shape(), var.dims()),
            ));
        }
        if view.dtype() != safetensors::Dtype::F32 {
            return Err(weights_error(path, format!("tensor `{name}` is {:?}, expected F32", view.dtype())));
        }
        let tensor = Tensor::from_raw_buffer(view.data(), DType::F32, view.shape(), &Device::Cpu)?;
        if tensor.flatten_all()?.to_vec1::<f32>()?.iter().any(|v| !v.is_finite()) {
            return Err(weights_error(path, format!("tensor `{name}` holds NaN or infinite values")));
        }
        var.set(&tensor)?;
    }
    let unknown: Vec<&str> = file.names().into_iter().filter(|n| !vars.contains_key(*n)).collect();
    if !unknown.is_empty() {
        return Err(weights_error(path, format!("tensors the configuration does not have: {}", unknown.join(", "))));
    }
    Ok(())
}

/// Writes every variable of `varmap` to `path` (through a temporary file and a rename).
pub fn save_weights(varmap: &VarMap, path: &Path) -> Result<()> {
    let tmp = path.with_extension("safetensors.tmp");
    varmap.save(&tmp)?;
    std::fs::rename(&tmp, path).map_err(|e| weights_error(path, format!("cannot rename {}: {e}", tmp.display())))
}

/// Every variable of `varmap` as plain named tensors (for baking).
pub fn varmap_tensors(varmap: &VarMap) -> Result<crate::bake::Tensors> {
    let vars = varmap.data().lock().expect("varmap lock poisoned");
    vars.iter()
        .map(|(name, var)| Ok((name.clone(), (var.dims().to_vec(), var.flatten_all()?.to_vec1::<f32>()?))))
        .collect()
}

/// Every f32 tensor of a safetensors file as plain named tensors.
pub fn read_tensors(path: &Path) -> Result<crate::bake::Tensors> {
    let bytes = std::fs::read(path).map_err(|e| weights_error(path, e.to_string()))?;
    let file = SafeTensors::deserialize(&bytes)
        .map_err(|e| weights_error(path, format!("not a valid safetensors file ({e})")))?;
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
