//! Weight averaging: an exponential moving average (EMA) of every variable, updated after each
//! optimiser step, which the trainer evaluates and checkpoints in place of the raw weights
//! (`--ema DECAY`). An average over the last few epochs smooths the noise of small-batch steps
//! on small data sets; its state is saved with the run so that `--resume` stays bit-exact.
//!
//! The decay warms up as `min(decay, (1 + t) / (10 + t))` at step `t`, so the first steps are not
//! dominated by the random initialisation.

use std::collections::HashMap;
use std::path::Path;

use candle_core::{Device, Tensor, Var};
use candle_nn::VarMap;

use crate::{Error, Result};

/// The moving average of a model's variables.
pub struct WeightAverage {
    decay: f64,
    entries: Vec<Entry>,
}

struct Entry {
    name: String,
    var: Var,
    average: Vec<f32>,
}

impl WeightAverage {
    /// Starts the average at the variables' current values.
    pub fn new(varmap: &VarMap, decay: f64) -> Result<Self> {
        if !(0.0..1.0).contains(&decay) {
            return Err(Error::Usage(format!("the weight-average decay must be in [0, 1), not {decay}")));
        }
        let vars = varmap.data().lock().expect("varmap lock poisoned");
        let mut entries = vars
            .iter()
            .map(|(name, var)| Ok(Entry { name: name.clone(), var: var.clone(), average: var.as_tensor().flatten_all()?.to_vec1()? }))
            .collect::<Result<Vec<_>>>()?;
        entries.sort_by(|a, b| a.name.cmp(&b.name));
        Ok(Self { decay, entries })
    }

    /// The decay at optimiser step `step` (counted from 1).
    fn decay_at(&self, step: usize) -> f32 {
        self.decay.min((1.0 + step as f64) / (10.0 + step as f64)) as f32
    }

    /// Folds the variables' values after optimiser step `step` into the average.
    pub fn update(&mut self, step: usize) -> Result<()> {
        let d = self.decay_at(step);
        for e in &mut self.entries {
            let now = e.var.as_tensor().flatten_all()?.to_vec1::<f32>()?;
            for (a, w) in e.average.iter_mut().zip(now) {
                *a = d * *a + (1.0 - d) * w;
            }
        }
        Ok(())
    }

    /// Exchanges the variables' values with the average: call it once to evaluate or save the
    /// averaged model, and again to continue training the raw weights.
    pub fn swap(&mut self) -> Result<()> {
        for e in &mut self.entries {
            let now = e.var.as_tensor().flatten_all()?.to_vec1::<f32>()?;
            let average = std::mem::replace(&mut e.average, now);
            e.var.set(&Tensor::from_vec(average, e.var.shape(), &Device::Cpu)?)?;
        }
        Ok(())
    }

    pub fn save(&self, path: &Path) -> Result<()> {
        let tensors: HashMap<String, Tensor> = self
            .entries
            .iter()
            .map(|e| Ok((e.name.clone(), Tensor::from_slice(&e.average, e.var.shape(), &Device::Cpu)?)))
            .collect::<Result<_>>()?;
        candle_core::safetensors::save(&tensors, path)?;
        Ok(())
    }

    pub fn load(&mut self, path: &Path) -> Result<()> {
        let mut tensors = candle_core::safetensors::load(path, &Device::Cpu)?;
        for e in &mut self.entries {
            let bad = |reason: String| Error::Checkpoint { path: path.to_path_buf(), reason };
            let t = tensors.remove(&e.name).ok_or_else(|| bad(format!("the weight average has no `{}`", e.name)))?;
            if t.elem_count() != e.average.len() {
                return Err(bad(format!("`{}` has {} values, not {}", e.name, t.elem_count(), e.average.len())));
            }
            e.average = t.flatten_all()?.to_vec1()?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::DType;
    use candle_nn::{Init, VarBuilder};

    fn one_var(value: f64) -> VarMap {
        let varmap = VarMap::new();
        let vb = VarBuilder::from_varmap(&varmap, DType::F32, &Device::Cpu);
        vb.get_with_hints(3, "w", Init::Const(value)).unwrap();
        varmap
    }

    fn values(varmap: &VarMap) -> Vec<f32> {
        varmap.data().lock().unwrap()["w"].as_tensor().to_vec1().unwrap()
    }

    #[test]
    fn follows_the_weights_with_the_warmed_up_decay_and_swaps_both_ways() {
        let varmap = one_var(0.0);
        let mut average = WeightAverage::new(&varmap, 0.9).unwrap();
        let var = varmap.data().lock().unwrap()["w"].clone();
        var.set(&Tensor::new(&[1f32, 2.0, 3.0], &Device::Cpu).unwrap()).unwrap();
        average.update(1).unwrap(); // decay 2/11
        let d = 2f32 / 11.0;
        let want: Vec<f32> = [1f32, 2.0, 3.0].iter().map(|w| d * 0.0 + (1.0 - d) * w).collect();
        average.swap().unwrap();
        assert_eq!(values(&varmap), want, "the average is in the variables");
        average.swap().unwrap();
        assert_eq!(values(&varmap), vec![1.0, 2.0, 3.0], "and the raw weights are back");
        for step in 2..200 {
            average.update(step).unwrap();
        }
        average.swap().unwrap();
        assert!(values(&varmap).iter().zip([1f32, 2.0, 3.0]).all(|(a, w)| (a - w).abs() < 1e-4), "a constant weight is its own average");
    }

    #[test]
    fn saves_and_loads_bit_for_bit_and_rejects_a_bad_decay() {
        let varmap = one_var(0.5);
        let mut average = WeightAverage::new(&varmap, 0.99).unwrap();
        varmap.data().lock().unwrap()["w"].set(&Tensor::new(&[0.1f32, -7.0, 1e-3], &Device::Cpu).unwrap()).unwrap();
        average.update(5).unwrap();
        let path = std::env::temp_dir().join(format!("pvt3-average-{}.safetensors", std::process::id()));
        average.save(&path).unwrap();
        let mut other = WeightAverage::new(&varmap, 0.99).unwrap();
        other.load(&path).unwrap();
        assert_eq!(other.entries[0].average, average.entries[0].average);
        std::fs::remove_file(path).unwrap();
        for bad in [1.0, -0.1, f64::NAN] {
            assert!(WeightAverage::new(&varmap, bad).is_err(), "{bad}");
        }
    }
}
