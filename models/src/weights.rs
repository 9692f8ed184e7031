//! Loading and saving a candle model's variables as safetensors under the golden names. Loading
//! checks every name and shape first and says which tensor does not fit; saving writes a
//! temporary file and renames it, so an existing file is never left half-written. Reading a
//! checkpoint as plain named tensors is `pvt3_spec::weights`.

use std::path::Path;

use candle_core::{Device, Tensor};
use candle_nn::VarMap;
use pvt3_spec::weights::{read_tensors, weights_error, Tensors};

use crate::Result;

/// Sets every variable of `varmap` from the safetensors file at `path`.
pub fn load_weights(varmap: &VarMap, path: &Path) -> Result<()> {
    set_vars(varmap, &read_tensors(path)?, path)
}

/// Sets every variable of `varmap` from `tensors` (read from `source`), after checking that every
/// name is there with the expected shape and finite values, and that nothing is left over.
pub fn set_vars(varmap: &VarMap, tensors: &Tensors, source: &Path) -> Result<()> {
    let vars = varmap.data().lock().expect("varmap lock poisoned");
    let mut names: Vec<&String> = vars.keys().collect();
    names.sort();
    for name in names {
        let var = &vars[name];
        let (shape, values) = tensors
            .get(name)
            .ok_or_else(|| weights_error(source, format!("tensor `{name}` is missing (a checkpoint of another model?)")))?;
        if shape.as_slice() != var.dims() {
            return Err(
                weights_error(source, format!("tensor `{name}` has shape {shape:?}, the configuration expects {:?}", var.dims())).into()
            );
        }
        if values.iter().any(|v| !v.is_finite()) {
            return Err(weights_error(source, format!("tensor `{name}` holds NaN or infinite values")).into());
        }
        var.set(&Tensor::from_vec(values.clone(), shape.as_slice(), &Device::Cpu)?)?;
    }
    let mut unknown: Vec<&str> = tensors.keys().map(String::as_str).filter(|n| !vars.contains_key(*n)).collect();
    if !unknown.is_empty() {
        unknown.sort_unstable();
        return Err(weights_error(source, format!("tensors the configuration does not have: {}", unknown.join(", "))).into());
    }
    Ok(())
}

/// Writes every variable of `varmap` to `path` (through a temporary file and a rename).
pub fn save_weights(varmap: &VarMap, path: &Path) -> Result<()> {
    let tmp = path.with_extension("safetensors.tmp");
    varmap.save(&tmp)?;
    Ok(std::fs::rename(&tmp, path).map_err(|e| weights_error(path, format!("cannot rename {}: {e}", tmp.display())))?)
}

/// Every variable of `varmap` as plain named tensors (for baking).
pub fn varmap_tensors(varmap: &VarMap) -> Result<Tensors> {
    let vars = varmap.data().lock().expect("varmap lock poisoned");
    vars.iter().map(|(name, var)| Ok((name.clone(), (var.dims().to_vec(), var.flatten_all()?.to_vec1::<f32>()?)))).collect()
}
