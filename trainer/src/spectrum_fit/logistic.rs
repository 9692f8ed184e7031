//! A multinomial logistic regression with an L2 penalty, fitted in full batch by Nesterov's
//! accelerated gradient: the linear map of a spectral head over an image's space, whose few
//! standardised features a convex fit reads better than the network's training does
//! (docs/camera.md, "The image's spectrum").

/// Passes over the training features; the loss has converged to a few digits well before.
const STEPS: usize = 600;

/// Weights `[classes, features]` row-major and biases `[classes]`.
pub struct Fit {
    pub weight: Vec<f64>,
    pub bias: Vec<f64>,
}

impl Fit {
    /// The classes' scores of one feature row.
    fn scores(&self, row: &[f64]) -> Vec<f64> {
        let f = row.len();
        self.bias
            .iter()
            .enumerate()
            .map(|(c, b)| b + self.weight[c * f..(c + 1) * f].iter().zip(row).map(|(w, x)| w * x).sum::<f64>())
            .collect()
    }

    /// The class each row scores highest.
    pub fn predict(&self, rows: &[Vec<f64>]) -> Vec<usize> {
        rows.iter().map(|r| argmax(&self.scores(r))).collect()
    }
}

fn argmax(v: &[f64]) -> usize {
    v.iter().enumerate().fold(0, |best, (i, x)| if *x > v[best] { i } else { best })
}

/// Minimises the mean cross-entropy of `rows` (features, standardised) against `labels` plus
/// `penalty / 2 · ‖weight‖²` (the biases unpenalised).
pub fn fit(rows: &[Vec<f64>], labels: &[usize], classes: usize, penalty: f64) -> Fit {
    let (n, f) = (rows.len(), rows.first().map_or(0, Vec::len));
    // The loss's curvature is at most half the largest eigenvalue of [x 1]ᵀ[x 1] / n (softmax's
    // Hessian is below ½ I), bounded by its trace; plus the penalty's.
    let trace: f64 = rows.iter().map(|r| 1.0 + r.iter().map(|x| x * x).sum::<f64>()).sum::<f64>() / n.max(1) as f64;
    let step = 1.0 / (0.5 * trace + penalty);
    let zero = || Fit { weight: vec![0.0; classes * f], bias: vec![0.0; classes] };
    let (mut at, mut before) = (zero(), zero());
    for k in 0..STEPS {
        // The look-ahead point of Nesterov's method, then a gradient step from it.
        let momentum = k as f64 / (k as f64 + 3.0);
        let ahead = Fit {
            weight: at.weight.iter().zip(&before.weight).map(|(a, b)| a + momentum * (a - b)).collect(),
            bias: at.bias.iter().zip(&before.bias).map(|(a, b)| a + momentum * (a - b)).collect(),
        };
        let (mut gw, mut gb) = (ahead.weight.iter().map(|w| penalty * w).collect::<Vec<_>>(), vec![0.0; classes]);
        for (row, &label) in rows.iter().zip(labels) {
            let scores = ahead.scores(row);
            let top = scores.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
            let exp: Vec<f64> = scores.iter().map(|s| (s - top).exp()).collect();
            let total: f64 = exp.iter().sum();
            for c in 0..classes {
                let residual = (exp[c] / total - f64::from(u8::from(c == label))) / n as f64;
                gb[c] += residual;
                gw[c * f..(c + 1) * f].iter_mut().zip(row).for_each(|(g, x)| *g += residual * x);
            }
        }
        before = std::mem::replace(
            &mut at,
            Fit {
                weight: ahead.weight.iter().zip(&gw).map(|(w, g)| w - step * g).collect(),
                bias: ahead.bias.iter().zip(&gb).map(|(b, g)| b - step * g).collect(),
            },
        );
    }
    at
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
