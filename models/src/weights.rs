//! Loading and saving model weights as safetensors under the golden names. Loading checks every
//! name and shape first and says which tensor does not fit; saving writes a temporary file and
//! renames it, so an existing file is never left half-written.

use std::path::Path;

use candle_core::{Device, Tensor};
use candle_nn::VarMap;
use safetensors::SafeTensors;

use crate::{Error, Result};

fn weights_error(path: &Path, reason: impl Into<String>) -> Error {
    Error::Weights { path: path.display().to_string(), reason: reason.into() }
}

/// Sets every variable of `varmap` from the safetensors file at `path`.
pub fn load_weights(varmap: &VarMap, path: &Path) -> Result<()> {
    set_vars(varmap, &read_tensors(path)?, path)
}

/// Sets every variable of `varmap` from `tensors` (read from `source`), after checking that every
/// name is there with the expected shape and finite values, and that nothing is left over.
pub fn set_vars(varmap: &VarMap, tensors: &crate::bake::Tensors, source: &Path) -> Result<()> {
    let vars = varmap.data().lock().expect("varmap lock poisoned");
    let mut names: Vec<&String> = vars.keys().collect();
    names.sort();
    for name in names {
        let var = &vars[name];
        let (shape, values) = tensors
            .get(name)
            .ok_or_else(|| weights_error(source, format!("tensor `{name}` is missing (a checkpoint of another model?)")))?;
        if shape.as_slice() != var.dims() {
            return Err(weights_error(source, format!("tensor `{name}` has shape {shape:?}, the configuration expects {:?}", var.dims())));
        }
        if values.iter().any(|v| !v.is_finite()) {
            return Err(weights_error(source, format!("tensor `{name}` holds NaN or infinite values")));
        }
        var.set(&Tensor::from_vec(values.clone(), shape.as_slice(), &Device::Cpu)?)?;
    }
    let mut unknown: Vec<&str> = tensors.keys().map(String::as_str).filter(|n| !vars.contains_key(*n)).collect();
    if !unknown.is_empty() {
        unknown.sort_unstable();
        return Err(weights_error(source, format!("tensors the configuration does not have: {}", unknown.join(", "))));
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
    vars.iter().map(|(name, var)| Ok((name.clone(), (var.dims().to_vec(), var.flatten_all()?.to_vec1::<f32>()?)))).collect()
}

/// Every f32 tensor of a safetensors file as plain named tensors.
pub fn read_tensors(path: &Path) -> Result<crate::bake::Tensors> {
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
