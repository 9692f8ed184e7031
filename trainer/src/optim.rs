//! AdamW with decoupled weight decay on matrices only (not on biases, norms, embeddings or the
//! selection masks), whose moment estimates can be saved and restored so that `--resume` continues
//! exactly where a run stopped. candle-nn's AdamW keeps its state private.
//!
//! The update runs as one loop per parameter rather than a dozen candle ops (each allocating a
//! tensor), applying every constant as candle's scalar ops do, so that it gives the same bits as
//! the tensor formula it replaced (a test holds it to that).

use std::collections::HashMap;
use std::path::Path;

use candle_core::backprop::GradStore;
use candle_core::{Device, Tensor, Var};
use candle_nn::VarMap;
use pvt3_spec::names::Role;

use crate::Result;

/// A linear layer's weight matrix ([`Role::Matrix`]): what weight decay and random pruning
/// apply to.
pub fn is_weight_matrix(name: &str, var: &Var) -> bool {
    Role::of(name, var.rank()) == Role::Matrix
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
    m: Vec<f32>,
    v: Vec<f32>,
}

impl AdamW {
    /// Every variable of `varmap`, each with its learning-rate multiple `lr_scale(name, var)`.
    pub fn new(varmap: &VarMap, weight_decay: f64, lr_scale: impl Fn(&str, &Var) -> f64) -> Result<Self> {
        let vars = varmap.data().lock().expect("varmap lock poisoned");
        let mut params = vars
            .iter()
            .map(|(name, var)| {
                let decay = is_weight_matrix(name, var);
                let zeros = vec![0f32; var.elem_count()];
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
        // Each constant as candle's scalar ops apply it: `v * mul + add` in f32, a division by
        // a scalar as a product with its reciprocal.
        let (scale, b1f, nb1, b2f, nb2) = (grad_scale as f32, b1 as f32, (1.0 - b1) as f32, b2 as f32, (1.0 - b2) as f32);
        let (ibc1, ibc2, eps) = ((1.0 / bc1) as f32, (1.0 / bc2) as f32, self.eps as f32);
        for p in &mut self.params {
            let Some(g) = grads.get(&p.var) else { continue };
            let g = g.flatten_all()?.to_vec1::<f32>()?;
            let lr = lr * p.lr_scale;
            let (keep, rate) = ((1.0 - lr * self.weight_decay) as f32, lr as f32);
            let mut theta = p.var.as_tensor().flatten_all()?.to_vec1::<f32>()?;
            for (i, t) in theta.iter_mut().enumerate() {
                let g = g[i] * scale + 0.0;
                p.m[i] = (p.m[i] * b1f + 0.0) + (g * nb1 + 0.0);
                p.v[i] = (p.v[i] * b2f + 0.0) + (g * g * nb2 + 0.0);
                let update = (p.m[i] * ibc1 + 0.0) / ((p.v[i] * ibc2 + 0.0).sqrt() * 1.0 + eps);
                let decayed = if p.decay { *t * keep + 0.0 } else { *t };
                *t = decayed - (update * rate + 0.0);
            }
            p.var.set(&Tensor::from_vec(theta, p.var.shape(), &Device::Cpu)?)?;
        }
        Ok(())
    }

    /// Saves the moment estimates (the step count goes with the run state).
    pub fn save(&self, path: &Path) -> Result<()> {
        let mut tensors = HashMap::new();
        for p in &self.params {
            tensors.insert(format!("m.{}", p.name), Tensor::from_slice(&p.m, p.var.shape(), &Device::Cpu)?);
            tensors.insert(format!("v.{}", p.name), Tensor::from_slice(&p.v, p.var.shape(), &Device::Cpu)?);
        }
        candle_core::safetensors::save(&tensors, path)?;
        Ok(())
    }

    pub fn load(&mut self, path: &Path, step: usize) -> Result<()> {
        let mut tensors = candle_core::safetensors::load(path, &Device::Cpu)?;
        for p in &mut self.params {
            let missing = |k: &str| crate::Error::Checkpoint { path: path.to_path_buf(), reason: format!("optimiser state has no `{k}`") };
            let (mk, vk) = (format!("m.{}", p.name), format!("v.{}", p.name));
            for (moment, key) in [(&mut p.m, &mk), (&mut p.v, &vk)] {
                let t = tensors.remove(key).ok_or_else(|| missing(key))?;
                if t.elem_count() != moment.len() {
                    return Err(crate::Error::Checkpoint {
                        path: path.to_path_buf(),
                        reason: format!("`{key}` has {} values, not {}", t.elem_count(), moment.len()),
                    });
                }
                *moment = t.flatten_all()?.to_vec1::<f32>()?;
            }
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

    #[test]
    fn the_update_is_the_tensor_formulas_bit_for_bit() {
        let varmap = VarMap::new();
        let vb = VarBuilder::from_varmap(&varmap, DType::F32, &Device::Cpu);
        let w = vb.get_with_hints((3, 4), "fc.weight", Init::Randn { mean: 0.0, stdev: 1.0 }).unwrap();
        let b = vb.get_with_hints(4, "fc.bias", Init::Randn { mean: 0.0, stdev: 1.0 }).unwrap();
        let mut opt = AdamW::new(&varmap, 0.05, |n, _| if n == "fc.bias" { 10.0 } else { 1.0 }).unwrap();
        // The formula as candle ops, as the optimiser computed it before it became a loop.
        let mut moments: Vec<(Tensor, Tensor)> = [&w, &b].iter().map(|t| (t.zeros_like().unwrap(), t.zeros_like().unwrap())).collect();
        let (b1, b2, eps, wd) = (0.9f64, 0.999f64, 1e-8f64, 0.05f64);
        for step in 1..=5 {
            let (lr, scale) = (1e-3 * step as f64, 0.7);
            let loss = ((&w * 3.0).unwrap().sin().unwrap().sum_all().unwrap() + b.sqr().unwrap().sum_all().unwrap()).unwrap();
            let grads = loss.backward().unwrap();
            let (bc1, bc2) = (1.0 - b1.powi(step), 1.0 - b2.powi(step));
            let want: Vec<Vec<f32>> = [(&w, 1.0, true), (&b, 10.0, false)]
                .iter()
                .zip(moments.iter_mut())
                .map(|((t, lr_scale, decay), (m, v))| {
                    let g = (grads.get(t).unwrap() * scale).unwrap();
                    *m = ((&*m * b1).unwrap() + (&g * (1.0 - b1)).unwrap()).unwrap();
                    *v = ((&*v * b2).unwrap() + (g.sqr().unwrap() * (1.0 - b2)).unwrap()).unwrap();
                    let update = ((&*m / bc1).unwrap() / ((&*v / bc2).unwrap().sqrt().unwrap() + eps).unwrap()).unwrap();
                    let lr = lr * lr_scale;
                    let theta = if *decay { (*t * (1.0 - lr * wd)).unwrap() } else { (*t).clone() };
                    (theta - (update * lr).unwrap()).unwrap().flatten_all().unwrap().to_vec1().unwrap()
                })
                .collect();
            opt.step(&grads, lr, scale).unwrap();
            for (t, want) in [&w, &b].iter().zip(want) {
                let got: Vec<u32> = t.flatten_all().unwrap().to_vec1::<f32>().unwrap().iter().map(|v| v.to_bits()).collect();
                assert_eq!(got, want.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), "step {step}");
            }
        }
    }
}
