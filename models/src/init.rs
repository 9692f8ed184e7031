//! Seeded initialisation of every variable, replacing candle's own (whose CPU generator cannot be
//! seeded). Linear layers follow PyTorch's default (uniform ±1/√fan_in for weight and bias), norms
//! masks and the spectral head's standardisation start at one and zero, and the CLS tokens and position embedding at std 0.02: std 1
//! there, as common ViViT code does, leaves the model at chance for many epochs. LSTM weights
//! and biases follow PyTorch too (uniform ±1/√hidden).

use candle_core::{DType, Device, Result, Tensor};
use candle_nn::{VarBuilder, VarMap};

use pvt3_spec::names::{self, Role};

use crate::{Config, Rng};

/// A model built by `new` on the CPU with its variables in a new [`VarMap`], seeded by `seed`.
pub fn seeded<M>(cfg: &Config, seed: u64, new: impl FnOnce(&Config, VarBuilder) -> crate::Result<M>) -> crate::Result<(M, VarMap)> {
    let varmap = VarMap::new();
    let model = new(cfg, VarBuilder::from_varmap(&varmap, DType::F32, &Device::Cpu))?;
    init_weights(&varmap, seed)?;
    Ok((model, varmap))
}

/// Overwrites every variable of `varmap` with values drawn from `seed`, in name order.
pub fn init_weights(varmap: &VarMap, seed: u64) -> Result<()> {
    let mut rng = Rng::new(seed);
    let vars = varmap.data().lock().expect("varmap lock poisoned").clone();
    let mut names: Vec<&String> = vars.keys().collect();
    names.sort();
    for name in names {
        let var = &vars[name];
        let shape = var.shape().clone();
        let n = shape.elem_count();
        let values: Vec<f32> = match Role::of(name, shape.rank()) {
            Role::Mask | Role::NormScale | Role::StandardScale => vec![1.0; n],
            Role::NormShift | Role::StandardShift => vec![0.0; n],
            Role::Embedding => (0..n).map(|_| 0.02 * rng.normal()).collect(),
            Role::Matrix | Role::Layer => {
                let (layer, leaf) = name.rsplit_once('.').unwrap_or(("", name));
                let fan_in = if names::LSTM.contains(&leaf) {
                    vars[&names::join(&[layer, names::WEIGHT_HH])].dims()[1]
                } else {
                    vars[&names::join(&[layer, names::WEIGHT])].dims()[1..].iter().product()
                };
                let bound = 1.0 / (fan_in as f32).sqrt();
                (0..n).map(|_| bound * (2.0 * rng.uniform() - 1.0)).collect()
            }
        };
        var.set(&Tensor::from_vec(values, shape, var.device())?)?;
    }
    Ok(())
}
