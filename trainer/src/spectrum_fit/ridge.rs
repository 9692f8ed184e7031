//! A ridge classifier in closed form: least squares from standardised features to targets of
//! ±1 (+1 for a row's class), with an L2 penalty, the rows and targets centred so that the biases
//! go unpenalised. The map of a head over an image's space that reads its pixels (thousands of
//! features, one row a training window): where the logistic regression's gradient steps would
//! need a pass over every feature for each of hundreds of steps, the ridge solves one system
//! per penalty, of the rows' count or the features' (the smaller), by Cholesky's factorisation.
//! It is what a user would try first on the pixels (`bench/pixel_ridge.py`, the anchor).

use ndarray::{Array1, Array2, Axis};

/// Weights `[classes, features]` and biases `[classes]`: a row's scores are `weight · row + bias`.
pub struct Ridge {
    pub weight: Array2<f64>,
    pub bias: Array1<f64>,
}

impl Ridge {
    /// Scores `[rows, classes]` of `rows` `[rows, features]`.
    pub fn scores(&self, rows: &Array2<f64>) -> Array2<f64> {
        rows.dot(&self.weight.t()) + &self.bias
    }
}

/// The ridge fits of `rows` `[n, features]` (standardised) against `labels`, one for each
/// strength: each minimises `‖X W − T‖² + strength · n · ‖W‖²` over the centred rows and targets.
pub fn fits(rows: &Array2<f64>, labels: &[usize], classes: usize, strengths: &[f64]) -> Vec<Ridge> {
    let n = rows.nrows();
    let mut targets = Array2::<f64>::from_elem((n, classes), -1.0);
    labels.iter().enumerate().for_each(|(i, l)| targets[[i, *l]] = 1.0);
    let (row_mean, target_mean) = (rows.mean_axis(Axis(0)).expect("training rows"), targets.mean_axis(Axis(0)).expect("training rows"));
    let x = rows - &row_mean;
    let t = targets - &target_mean;
    // The dual `Xᵀ (X Xᵀ + λ I)⁻¹ T` where the rows are fewer than the features, else the primal
    // `(Xᵀ X + λ I)⁻¹ Xᵀ T`: the same weights, from the smaller system.
    let dual = n < x.ncols();
    let (gram, right) = if dual { (x.dot(&x.t()), t) } else { (x.t().dot(&x), x.t().dot(&t)) };
    strengths
        .iter()
        .map(|s| {
            let mut system = gram.clone();
            system.diag_mut().mapv_inplace(|d| d + s * n as f64);
            let solved = cholesky_solve(system, &right);
            let weight = if dual { x.t().dot(&solved) } else { solved }.reversed_axes();
            let bias = &target_mean - &weight.dot(&row_mean);
            Ridge { weight: weight.as_standard_layout().to_owned(), bias }
        })
        .collect()
}

/// `A⁻¹ B` for a symmetric positive definite `A` (a ridge system, its diagonal raised by the
/// penalty), by Cholesky's factorisation `A = L Lᵀ`, then the two triangular solves.
fn cholesky_solve(a: Array2<f64>, b: &Array2<f64>) -> Array2<f64> {
    let n = a.nrows();
    // L row by row (row-major, the lower triangle): each entry below the diagonal is a dot
    // product of two rows' prefixes, both contiguous.
    let mut l = a.as_standard_layout().into_owned().into_raw_vec_and_offset().0;
    for j in 0..n {
        let (row_j, below) = l[j * n..].split_at_mut(n);
        let d = (row_j[j] - dot(&row_j[..j], &row_j[..j])).sqrt();
        row_j[j] = d;
        for row_i in below.chunks_mut(n) {
            row_i[j] = (row_i[j] - dot(&row_i[..j], &row_j[..j])) / d;
        }
    }
    let l = Array2::from_shape_vec((n, n), l).expect("a square matrix");
    // L y = B, then Lᵀ x = y.
    let mut y = b.to_owned();
    for i in 0..n {
        let above = l.slice(ndarray::s![i, ..i]).dot(&y.slice(ndarray::s![..i, ..]));
        let mut row = y.row_mut(i);
        row -= &above;
        row /= l[[i, i]];
    }
    for i in (0..n).rev() {
        let below = l.slice(ndarray::s![i + 1.., i]).dot(&y.slice(ndarray::s![i + 1.., ..]));
        let mut row = y.row_mut(i);
        row -= &below;
        row /= l[[i, i]];
    }
    y
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The factorisation solves what it is given: `A (A⁻¹ B) = B` for a matrix `Mᵀ M + I`.
    #[test]
    fn cholesky_solves_a_symmetric_positive_definite_system() {
        let m = Array2::from_shape_fn((7, 5), |(i, j)| ((i * 5 + j * 3) % 7) as f64 - 3.0);
        let a = m.t().dot(&m) + Array2::<f64>::eye(5);
        let b = Array2::from_shape_fn((5, 2), |(i, j)| (i + 2 * j) as f64);
        let x = cholesky_solve(a.clone(), &b);
        let back = a.dot(&x);
        assert!(back.iter().zip(b.iter()).all(|(u, v)| (u - v).abs() < 1e-9), "{back:?}");
    }

    /// The dual (fewer rows than features) and the primal give the same weights, and a weak
    /// penalty separates classes apart along one feature.
    #[test]
    fn the_dual_and_the_primal_agree() {
        let rows =
            Array2::from_shape_fn((6, 8), |(i, j)| if j == 0 { (i % 2) as f64 * 2.0 - 1.0 } else { ((i * 3 + j * 5) % 7) as f64 / 7.0 });
        let labels: Vec<usize> = (0..6).map(|i| i % 2).collect();
        let few = fits(&rows, &labels, 2, &[1e-3]).remove(0);
        // The same rows twice: more rows than features (the primal), the same fit.
        let twice = ndarray::concatenate(Axis(0), &[rows.view(), rows.view()]).unwrap();
        let many = fits(&twice, &[labels.clone(), labels.clone()].concat(), 2, &[1e-3]).remove(0);
        assert!(few.weight.iter().zip(many.weight.iter()).all(|(a, b)| (a - b).abs() < 1e-6), "{:?} {:?}", few.weight, many.weight);
        let predicted: Vec<usize> = few.scores(&rows).rows().into_iter().map(|r| if r[1] > r[0] { 1 } else { 0 }).collect();
        assert_eq!(predicted, labels);
    }
}
