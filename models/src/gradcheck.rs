//! Test helpers for the fused ops: random variables and inputs, error measures, and a
//! directional derivative by finite differences.

use candle_core::{Device, Tensor, Var};
use candle_nn::VarMap;

use crate::Rng;

/// Every variable of `varmap` set at random (masks and norm weights around 1, the rest around 0,
/// so that gradients are tested away from initial values), by name.
pub fn randomise(varmap: &VarMap, seed: u64) -> Vec<(String, Var)> {
    let mut rng = Rng::new(seed);
    let mut vars: Vec<(String, Var)> = varmap.data().lock().unwrap().iter().map(|(n, v)| (n.clone(), v.clone())).collect();
    vars.sort_by(|a, b| a.0.cmp(&b.0));
    for (name, var) in &vars {
        let centre = if name.ends_with("mask") || name.ends_with("norm.weight") { 1.0 } else { 0.0 };
        let values: Vec<f32> = (0..var.elem_count()).map(|_| centre + 0.3 * rng.normal()).collect();
        var.set(&Tensor::from_vec(values, var.shape(), &Device::Cpu).unwrap()).unwrap();
    }
    vars
}

pub fn random(shape: &[usize], seed: u64) -> Tensor {
    let mut rng = Rng::new(seed);
    let n = shape.iter().product();
    Tensor::from_vec((0..n).map(|_| rng.normal()).collect::<Vec<f32>>(), shape, &Device::Cpu).unwrap()
}

pub fn max_abs(t: &Tensor) -> f32 {
    t.abs().unwrap().flatten_all().unwrap().max(0).unwrap().to_scalar::<f32>().unwrap()
}

/// `max |a − b| / max |b|`.
pub fn relative(a: &Tensor, b: &Tensor) -> f32 {
    max_abs(&(a - b).unwrap()) / max_abs(b).max(1e-30)
}

/// The derivative of `loss` along a random unit direction of `var` by central differences (with
/// Richardson's extrapolation, which cancels the h² error so that the step can stay large against
/// f32 rounding), and the same from `gradient`; `var` is left as it was.
pub fn directional(var: &Var, gradient: &Tensor, seed: u64, loss: impl Fn() -> f64) -> (f64, f64) {
    let direction = random(var.dims(), seed);
    let direction = (&direction / direction.sqr().unwrap().sum_all().unwrap().sqrt().unwrap().to_scalar::<f32>().unwrap() as f64).unwrap();
    let analytic = (gradient * &direction).unwrap().sum_all().unwrap().to_scalar::<f32>().unwrap() as f64;
    let original = var.as_tensor().copy().unwrap();
    let central = |h: f64| {
        let at = |t: f64| {
            var.set(&(&original + (&direction * t).unwrap()).unwrap()).unwrap();
            loss()
        };
        (at(h) - at(-h)) / (2.0 * h)
    };
    let numeric = (4.0 * central(5e-3) - central(1e-2)) / 3.0;
    var.set(&original).unwrap();
    (numeric, analytic)
}

/// A smooth scalar of `y`: `Σ tanh(y · weights)`, in f64.
pub fn smooth_loss(y: &Tensor, weights: &Tensor) -> f64 {
    let y: Vec<f32> = y.flatten_all().unwrap().to_vec1().unwrap();
    let w: Vec<f32> = weights.flatten_all().unwrap().to_vec1().unwrap();
    y.iter().zip(&w).map(|(a, b)| (*a as f64 * *b as f64).tanh()).sum()
}
