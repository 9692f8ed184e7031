//! AdamW with decoupled weight decay on matrices only (not on biases, norms, embeddings or the
//! selection masks), whose moment estimates can be saved and restored so that `--resume` continues
//! exactly where a run stopped. candle-nn's AdamW keeps its state private.

use std::collections::HashMap;
use std::path::Path;

use candle_core::backprop::GradStore;
use candle_core::{Device, Tensor, Var};
use candle_nn::VarMap;

use crate::Result;

/// A linear layer's weight matrix: what weight decay (and random pruning) applies to.
pub fn is_weight_matrix(name: &str, var: &Var) -> bool {
    name.ends_with(".weight") && var.rank() == 2
}

pub struct AdamW {
    params: Vec<Param>,
    pub step: usize,
    pub weight_decay: f64,
    beta1: f64,
    beta2: f64,
    eps: f64,
}

struct Param {
    name: String,
    var: Var,
    decay: bool,
    /// This parameter's learning rate as a multiple of the schedule's.
    lr_scale: f64,
    m: Tensor,
    v: Tensor,
}

impl AdamW {
    /// Every variable of `varmap`, each with its learning-rate multiple `lr_scale(name, var)`.
    pub fn new(varmap: &VarMap, weight_decay: f64, lr_scale: impl Fn(&str, &Var) -> f64) -> Result<Self> {
        let vars = varmap.data().lock().expect("varmap lock poisoned");
        let mut params = vars
            .iter()
            .map(|(name, var)| {
                let decay = is_weight_matrix(name, var);
                let zeros = var.zeros_like()?;
                let lr_scale = lr_scale(name, var);
                Ok(Param { name: name.clone(), var: var.clone(), decay, lr_scale, m: zeros.clone(), v: zeros })
            })
            .collect::<Result<Vec<_>>>()?;
        params.sort_by(|a, b| a.name.cmp(&b.name));
        Ok(Self { params, step: 0, weight_decay, beta1: 0.9, beta2: 0.999, eps: 1e-8 })
    }

    /// The global L2 norm of the gradients.
    pub fn grad_norm(&self, grads: &GradStore) -> Result<f64> {
        let mut total = 0f64;
        for p in &self.params {
            if let Some(g) = grads.get(&p.var) {
                total += g.sqr()?.sum_all()?.to_scalar::<f32>()? as f64;
            }
        }
        Ok(total.sqrt())
    }

    /// One update with learning rate `lr`, the gradients scaled by `grad_scale` (for clipping).
    pub fn step(&mut self, grads: &GradStore, lr: f64, grad_scale: f64) -> Result<()> {
        self.step += 1;
        let (b1, b2) = (self.beta1, self.beta2);
        let bc1 = 1.0 - b1.powi(self.step as i32);
        let bc2 = 1.0 - b2.powi(self.step as i32);
        for p in &mut self.params {
            let Some(g) = grads.get(&p.var) else { continue };
            let g = (g * grad_scale)?;
            p.m = ((&p.m * b1)? + (&g * (1.0 - b1))?)?;
            p.v = ((&p.v * b2)? + (g.sqr()? * (1.0 - b2))?)?;
            let update = ((&p.m / bc1)? / ((&p.v / bc2)?.sqrt()? + self.eps)?)?;
            let lr = lr * p.lr_scale;
            let mut theta = p.var.as_tensor().clone();
            if p.decay {
                theta = (theta * (1.0 - lr * self.weight_decay))?;
            }
            p.var.set(&(theta - (update * lr)?)?)?;
        }
        Ok(())
    }

    /// Saves the moment estimates (the step count goes with the run state).
    pub fn save(&self, path: &Path) -> Result<()> {
        let mut tensors = HashMap::new();
        for p in &self.params {
            tensors.insert(format!("m.{}", p.name), p.m.clone());
            tensors.insert(format!("v.{}", p.name), p.v.clone());
        }
        candle_core::safetensors::save(&tensors, path)?;
        Ok(())
    }

    pub fn load(&mut self, path: &Path, step: usize) -> Result<()> {
        let mut tensors = candle_core::safetensors::load(path, &Device::Cpu)?;
        for p in &mut self.params {
            let missing = |k: &str| crate::Error::Checkpoint { path: path.to_path_buf(), reason: format!("optimiser state has no `{k}`") };
            let (mk, vk) = (format!("m.{}", p.name), format!("v.{}", p.name));
            p.m = tensors.remove(&mk).ok_or_else(|| missing(&mk))?;
            p.v = tensors.remove(&vk).ok_or_else(|| missing(&vk))?;
        }
        self.step = step;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::DType;
    use candle_nn::{Init, VarBuilder};

    #[test]
    fn minimises_a_quadratic_and_decays_only_matrices() {
        let varmap = VarMap::new();
        let vb = VarBuilder::from_varmap(&varmap, DType::F32, &Device::Cpu);
        let w = vb.get_with_hints((2, 2), "fc.weight", Init::Const(1.0)).unwrap();
        let b = vb.get_with_hints(2, "fc.bias", Init::Const(1.0)).unwrap();
        let mut opt = AdamW::new(&varmap, 0.1, |_, _| 1.0).unwrap();
        // Adam's first step moves every value by lr against the gradient's sign; the matrix
        // alone is also decayed by lr × weight_decay.
        let loss = (w.sum_all().unwrap() + b.sum_all().unwrap()).unwrap();
        opt.step(&loss.backward().unwrap(), 0.1, 1.0).unwrap();
        let vars = varmap.data().lock().unwrap().clone();
        let w00 = vars["fc.weight"].as_tensor().to_vec2::<f32>().unwrap()[0][0];
        assert!((w00 - (0.99 - 0.1)).abs() < 1e-5, "{w00}");
        let b0 = vars["fc.bias"].as_tensor().to_vec1::<f32>().unwrap()[0];
        assert!((b0 - 0.9).abs() < 1e-5, "{b0}");
        // A quadratic bowl around 3 is found.
        for _ in 0..500 {
            let b = vars["fc.bias"].as_tensor();
            let loss = (b - 3.0).unwrap().sqr().unwrap().sum_all().unwrap();
            opt.step(&loss.backward().unwrap(), 0.05, 1.0).unwrap();
        }
        let got = vars["fc.bias"].as_tensor().to_vec1::<f32>().unwrap();
        assert!(got.iter().all(|v| (v - 3.0).abs() < 0.05), "{got:?}");
    }
}
