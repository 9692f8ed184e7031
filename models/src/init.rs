//! Seeded initialisation of every variable, replacing candle's own (whose CPU generator cannot be
//! seeded). Linear layers follow PyTorch's default (uniform ±1/√fan_in for weight and bias), norms
//! and masks start at one and zero, and the CLS tokens and position embedding at std 0.02: std 1
//! there, as common ViViT code does, leaves the model at chance for many epochs.

use candle_core::{Result, Tensor};
use candle_nn::VarMap;

use crate::Rng;

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
        let values: Vec<f32> = if name.ends_with("mask") || is_norm(name, "weight") {
            vec![1.0; n]
        } else if is_norm(name, "bias") {
            vec![0.0; n]
        } else if name == "pos_embed" || name.ends_with("_cls") {
            (0..n).map(|_| 0.02 * rng.normal()).collect()
        } else {
            let layer = name.rsplit_once('.').map_or(name.as_str(), |(l, _)| l);
            let fan_in = vars[&format!("{layer}.weight")].dims()[1];
            let bound = 1.0 / (fan_in as f32).sqrt();
            (0..n).map(|_| bound * (2.0 * rng.uniform() - 1.0)).collect()
        };
        var.set(&Tensor::from_vec(values, shape, var.device())?)?;
    }
    Ok(())
}

fn is_norm(name: &str, leaf: &str) -> bool {
    name.strip_suffix(leaf).is_some_and(|layer| layer.ends_with("norm."))
}
