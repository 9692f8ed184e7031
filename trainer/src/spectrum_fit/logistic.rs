//! A multinomial logistic regression with an L2 penalty, fitted in full batch by Nesterov's
//! accelerated gradient: the linear map of a spectral head over an image's space, whose few
//! standardised features a convex fit reads better than the network's training does
//! (docs/camera.md, "The image's spectrum"). Each pass is two matrix products (ndarray's), so
//! that a fit to every frame of the training touches (thousands of rows) takes seconds.

use ndarray::{Array1, Array2, Axis};

/// Passes over the training features; the loss has converged to a few digits well before.
const STEPS: usize = 600;

/// Weights `[classes, features]` row-major and biases `[classes]`.
pub struct Fit {
    pub weight: Vec<f64>,
    pub bias: Vec<f64>,
}

impl Fit {
    /// The class each row scores highest.
    pub fn predict(&self, rows: &[Vec<f64>]) -> Vec<usize> {
        self.logits(rows).rows().into_iter().map(|r| argmax(r.as_slice().expect("a standard layout"))).collect()
    }

    /// The logits `[rows, classes]` of `rows`.
    pub fn logits(&self, rows: &[Vec<f64>]) -> Array2<f64> {
        let (classes, f) = (self.bias.len(), rows.first().map_or(0, Vec::len));
        let weight = Array2::from_shape_vec((classes, f), self.weight.clone()).expect("weights of the rows' width");
        matrix(rows).dot(&weight.t()) + &Array1::from_vec(self.bias.clone())
    }
}

fn argmax(v: &[f64]) -> usize {
    v.iter().enumerate().fold(0, |best, (i, x)| if *x > v[best] { i } else { best })
}

/// The rows as one `[n, features]` matrix.
fn matrix(rows: &[Vec<f64>]) -> Array2<f64> {
    let f = rows.first().map_or(0, Vec::len);
    Array2::from_shape_vec((rows.len(), f), rows.concat()).expect("rows of one width")
}

/// Minimises the mean cross-entropy of `rows` (features, standardised) against `labels` plus
/// `penalty / 2 · ‖weight‖²` (the biases unpenalised).
pub fn fit(rows: &[Vec<f64>], labels: &[usize], classes: usize, penalty: f64) -> Fit {
    let (n, f) = (rows.len(), rows.first().map_or(0, Vec::len));
    let x = matrix(rows);
    let mut targets = Array2::<f64>::zeros((n, classes));
    labels.iter().enumerate().for_each(|(i, l)| targets[[i, *l]] = 1.0);
    // The loss's curvature is at most half the largest eigenvalue of [x 1]ᵀ[x 1] / n (softmax's
    // Hessian is below ½ I), bounded by its trace; plus the penalty's.
    let trace: f64 = rows.iter().map(|r| 1.0 + r.iter().map(|x| x * x).sum::<f64>()).sum::<f64>() / n.max(1) as f64;
    let step = 1.0 / (0.5 * trace + penalty);
    let (mut w, mut b) = (Array2::<f64>::zeros((classes, f)), Array1::<f64>::zeros(classes));
    let (mut w_before, mut b_before) = (w.clone(), b.clone());
    for k in 0..STEPS {
        // The look-ahead point of Nesterov's method, then a gradient step from it.
        let momentum = k as f64 / (k as f64 + 3.0);
        let w_ahead = &w + &((&w - &w_before) * momentum);
        let b_ahead = &b + &((&b - &b_before) * momentum);
        let mut p = x.dot(&w_ahead.t()) + &b_ahead;
        for mut row in p.rows_mut() {
            let top = row.fold(f64::NEG_INFINITY, |m, v| m.max(*v));
            row.mapv_inplace(|s| (s - top).exp());
            let total = row.sum();
            row /= total;
        }
        let residual = (p - &targets) / n as f64;
        let gw = residual.t().dot(&x) + &w_ahead * penalty;
        let gb = residual.sum_axis(Axis(0));
        w_before = std::mem::replace(&mut w, w_ahead - gw * step);
        b_before = std::mem::replace(&mut b, b_ahead - gb * step);
    }
    Fit { weight: w.into_raw_vec_and_offset().0, bias: b.to_vec() }
}
#[cfg(test)]
mod tests {
    use super::*;

    /// Two classes apart along the first feature and mixed along the second: the fit separates
    /// them by the first, and a stronger penalty gives smaller weights.
    #[test]
    fn separates_what_is_separable_and_shrinks_with_the_penalty() {
        let rows: Vec<Vec<f64>> =
            (0..40).map(|i| vec![if i % 2 == 0 { -1.0 } else { 1.0 } + 0.1 * (i % 5) as f64, ((i * 7) % 11) as f64 / 5.0 - 1.0]).collect();
        let labels: Vec<usize> = (0..40).map(|i| i % 2).collect();
        let loose = fit(&rows, &labels, 2, 1e-3);
        assert_eq!(loose.predict(&rows), labels);
        assert!((loose.weight[0] - loose.weight[2]).abs() > 4.0 * (loose.weight[1] - loose.weight[3]).abs(), "{:?}", loose.weight);
        let tight = fit(&rows, &labels, 2, 1.0);
        let norm = |w: &[f64]| w.iter().map(|v| v * v).sum::<f64>();
        assert!(norm(&tight.weight) < norm(&loose.weight) / 4.0);
    }
}
