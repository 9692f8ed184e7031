//! Dense layers, norms and GELU as ONNX nodes, and the weight algebra that keeps work out of the
//! graph. A norm's scale and bias move into the next product ([`absorb_norm`]). Centring
//! ([`centred`]) gives every write to the residual stream a zero mean over the features, so the
//! stream itself always has a zero mean, and each pre-norm is a root-mean-square norm
//! ([`rms_norm`]). tract runs that as one fused kernel, where a layer norm costs a sum, a
//! subtraction and a norm.

use pvt3_spec::baked::{Dense, Norm};

use pvt3_format::onnx::{float, int, ints, Op};

use crate::graph::Graph;

/// `x Wᵀ + b` on rows `[…, cols]`.
pub(crate) fn linear(g: &mut Graph, x: &str, l: &Dense, hint: &str) -> String {
    let wt: Vec<f32> = (0..l.cols).flat_map(|c| (0..l.rows).map(move |r| (r, c))).map(|(r, c)| l.weight[r * l.cols + c]).collect();
    let w = g.f32s(&format!("{hint}_w"), &[l.cols, l.rows], wt);
    let y = g.op(Op::MatMul, &[x, &w]);
    add_bias(g, &y, l, &[l.rows], hint)
}

/// `W x + b` on feature-major `x` `[cols, n]`: the transposed product, `[rows, n]`.
pub(crate) fn linear_columns(g: &mut Graph, x: &str, l: &Dense, hint: &str) -> String {
    let w = g.f32s(&format!("{hint}_w"), &[l.rows, l.cols], l.weight.clone());
    let y = g.op(Op::MatMul, &[&w, x]);
    add_bias(g, &y, l, &[l.rows, 1], hint)
}

/// `y` plus the bias of `l`, if it has one, shaped `dims` to broadcast along `y`.
fn add_bias(g: &mut Graph, y: &str, l: &Dense, dims: &[usize], hint: &str) -> String {
    match &l.bias {
        Some(b) => {
            let b = g.f32s(&format!("{hint}_b"), dims, b.clone());
            g.op(Op::Add, &[y, &b])
        }
        None => y.to_string(),
    }
}

/// `x + (y Wᵀ + b)`, the residual update by the layer `l`, written `x - (y (-W)ᵀ - b)`. tract
/// fuses an Add that follows a product into the product's store, which ran at half the speed of
/// the product and a separate sum (iCub rows: 19 µs against 9 + 1); it leaves a Sub alone.
pub(crate) fn residual_linear(g: &mut Graph, x: &str, y: &str, l: &Dense, hint: &str) -> String {
    let negated =
        Dense { weight: l.weight.iter().map(|w| -w).collect(), bias: l.bias.as_ref().map(|b| b.iter().map(|v| -v).collect()), ..l.clone() };
    let update = linear(g, y, &negated, hint);
    g.op(Op::Sub, &[x, &update])
}

/// A full layer norm with scale and bias, for rows whose mean is not known to be zero.
pub(crate) fn layer_norm(g: &mut Graph, x: &str, n: &Norm, eps: f64, hint: &str) -> String {
    let d = n.weight.len();
    let w = g.f32s(&format!("{hint}_scale"), &[d], n.weight.clone());
    let b = g.f32s(&format!("{hint}_bias"), &[d], n.bias.clone());
    g.node(Op::LayerNormalization, &[x, &w, &b], vec![int("axis", -1), float("epsilon", eps as f32)], None)
}

/// `x / √(mean(x²) + ε)` over the last axis: the layer norm of rows with zero mean, without its
/// scale and bias. Written as the pattern tract fuses into its `RmsNorm` kernel.
pub(crate) fn rms_norm(g: &mut Graph, x: &str, eps: f64) -> String {
    let eps = g.f32s("eps", &[], vec![eps as f32]);
    let squares = g.op(Op::Mul, &[x, x]);
    // Opset 17's ReduceMean takes its axes as an attribute (ReduceSum as an input).
    let mean = g.node(Op::ReduceMean, &[&squares], vec![ints("axes", &[-1]), int("keepdims", 1)], None);
    let shifted = g.op(Op::Add, &[&mean, &eps]);
    let root = g.op(Op::Sqrt, &[&shifted]);
    g.op(Op::Div, &[x, &root])
}

/// `l` applied after the affine part of `n`: `W (γ ∘ x + β) + b = (W diag γ) x + (W β + b)`.
pub(crate) fn absorb_norm(l: &Dense, n: &Norm) -> Dense {
    let weight = (0..l.rows * l.cols).map(|i| l.weight[i] * n.weight[i % l.cols]).collect();
    let bias = (0..l.rows)
        .map(|r| {
            let shift: f64 = (0..l.cols).map(|c| l.weight[r * l.cols + c] as f64 * n.bias[c] as f64).sum();
            (l.bias.as_ref().map_or(0.0, |b| b[r] as f64) + shift) as f32
        })
        .collect();
    Dense { weight, bias: Some(bias), ..l.clone() }
}

/// The affine part of a norm, `γ ∘ x + β`, as a dense layer.
pub(crate) fn norm_affine(n: &Norm) -> Dense {
    let d = n.weight.len();
    let weight = (0..d * d).map(|i| if i / d == i % d { n.weight[i / d] } else { 0.0 }).collect();
    Dense { rows: d, cols: d, weight, bias: Some(n.bias.clone()) }
}

/// `l` followed by subtracting the mean of its outputs: each weight column and the bias lose
/// their mean over the output rows.
pub(crate) fn centred(l: &Dense) -> Dense {
    let mut weight = l.weight.clone();
    for c in 0..l.cols {
        let mean = (0..l.rows).map(|r| l.weight[r * l.cols + c] as f64).sum::<f64>() / l.rows as f64;
        (0..l.rows).for_each(|r| weight[r * l.cols + c] = (l.weight[r * l.cols + c] as f64 - mean) as f32);
    }
    Dense { weight, bias: l.bias.as_ref().map(|b| centre_rows(b, l.rows)), ..l.clone() }
}

/// Each row of `d` values minus its mean.
pub(crate) fn centre_rows(v: &[f32], d: usize) -> Vec<f32> {
    v.chunks(d)
        .flat_map(|row| {
            let mean = row.iter().map(|x| *x as f64).sum::<f64>() / d as f64;
            row.iter().map(move |x| (*x as f64 - mean) as f32)
        })
        .collect()
}

/// GELU, erf form.
pub(crate) fn gelu(g: &mut Graph, x: &str) -> String {
    let root2 = g.f32s("sqrt2", &[], vec![std::f32::consts::SQRT_2]);
    let one = g.f32s("one", &[], vec![1.0]);
    let half = g.f32s("half", &[], vec![0.5]);
    let scaled = g.op(Op::Div, &[x, &root2]);
    let erf = g.op(Op::Erf, &[&scaled]);
    let plus = g.op(Op::Add, &[&erf, &one]);
    let prod = g.op(Op::Mul, &[x, &plus]);
    g.op(Op::Mul, &[&prod, &half])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centring_removes_the_mean_of_the_outputs_and_nothing_else() {
        let l = Dense { rows: 3, cols: 2, weight: vec![1.0, 2.0, 4.0, -1.0, 7.0, 0.5], bias: Some(vec![0.5, 1.5, -2.0]) };
        let c = centred(&l);
        let x = [0.3f64, -1.7];
        let out = |l: &Dense| -> Vec<f64> {
            (0..3).map(|r| l.bias.as_ref().unwrap()[r] as f64 + (0..2).map(|k| l.weight[r * 2 + k] as f64 * x[k]).sum::<f64>()).collect()
        };
        let (y, yc) = (out(&l), out(&c));
        let mean = y.iter().sum::<f64>() / 3.0;
        for (a, b) in y.iter().zip(&yc) {
            assert!((a - mean - b).abs() < 1e-6, "{a} - {mean} != {b}");
        }
        assert!(yc.iter().sum::<f64>().abs() < 1e-6);
    }

    #[test]
    fn a_norm_affine_is_a_diagonal_layer() {
        let n = Norm { weight: vec![2.0, 3.0], bias: vec![0.5, -1.0] };
        let l = norm_affine(&n);
        assert_eq!(l.weight, vec![2.0, 0.0, 0.0, 3.0]);
        assert_eq!(l.bias, Some(vec![0.5, -1.0]));
    }
}
