//! [`RealDft`]: the spectral head's transform (the ONNX `DFT` op as the exporter writes it: a
//! forward, two-sided transform of a real signal `[…, n, 1]` along its next-to-last axis, to
//! `[…, n, 2]`), with its FFT planned once, when the plan is built: rustfft's with the `spectral`
//! feature (the default build), else the runtime's own (`small_fft`, the small robot build), so
//! that every build runs every file.
//!
//! tract-core's own `Fft` plans the transform again at every run and walks the tensor through
//! per-element slices: 112 µs of a BioTac window's 339 (19 transforms of 400 frames,
//! `cargo run --release -p pvt3-bench-tools --bin profile`). Planned once over contiguous rows,
//! the same rustfft transform takes 7.7 µs for all 19 (docs/benchmarks.md).

#[cfg(feature = "spectral")]
use std::sync::Arc;

#[cfg(feature = "spectral")]
use rustfft::{num_complex::Complex, Fft, FftPlanner};
use tract_core::internal::*;

/// The transform of every row of `n` real values of the input.
#[derive(Clone)]
pub(crate) struct RealDft {
    n: usize,
    #[cfg(feature = "spectral")]
    fft: Arc<dyn Fft<f32>>,
    #[cfg(not(feature = "spectral"))]
    fft: crate::small_fft::RealFft,
}

impl RealDft {
    /// The transform of rows of `n` values.
    pub(crate) fn new(n: usize) -> Self {
        #[cfg(feature = "spectral")]
        let fft = FftPlanner::new().plan_fft_forward(n);
        #[cfg(not(feature = "spectral"))]
        let fft = crate::small_fft::RealFft::new(n);
        Self { n, fft }
    }

    /// The transform of each row of `real` into `out`, real and imaginary parts in turn.
    #[cfg(feature = "spectral")]
    fn transform(&self, real: &[f32], out: &mut Vec<f32>) {
        let mut row = vec![Complex::new(0.0, 0.0); self.n];
        let mut scratch = vec![Complex::new(0.0, 0.0); self.fft.get_inplace_scratch_len()];
        for values in real.chunks_exact(self.n) {
            row.iter_mut().zip(values).for_each(|(c, v)| *c = Complex::new(*v, 0.0));
            self.fft.process_with_scratch(&mut row, &mut scratch);
            out.extend(row.iter().flat_map(|c| [c.re, c.im]));
        }
    }

    /// The transform of each row of `real` into `out`, real and imaginary parts in turn.
    #[cfg(not(feature = "spectral"))]
    fn transform(&self, real: &[f32], out: &mut Vec<f32>) {
        out.resize(2 * real.len(), 0.0);
        self.fft.transform(real, out);
    }
}

impl std::fmt::Debug for RealDft {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "RealDft({})", self.n)
    }
}

// The plan is a function of `n` alone.
impl PartialEq for RealDft {
    fn eq(&self, other: &Self) -> bool {
        self.n == other.n
    }
}

impl Eq for RealDft {}

impl std::hash::Hash for RealDft {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.n.hash(state)
    }
}

impl Op for RealDft {
    fn name(&self) -> StaticName {
        "RealDft".into()
    }

    op_as_typed_op!();
}

impl EvalOp for RealDft {
    op_out_of_plan!();

    fn eval(&self, _ctx: &EvalContext, inputs: TVec<TValue>) -> TractResult<TVec<TValue>> {
        let x = args_1!(inputs);
        let view = x.to_plain_array_view::<f32>()?;
        let real = view.as_slice().context("a tensor in standard layout")?;
        let mut shape: TVec<usize> = x.shape().into();
        *shape.last_mut().context("a signal of rank 2 or more")? = 2;
        let mut out = Vec::with_capacity(2 * real.len());
        self.transform(real, &mut out);
        Ok(tvec!(Tensor::from_shape(&shape, &out)?.into_tvalue()))
    }
}

impl TypedOp for RealDft {
    fn output_facts(&self, inputs: &[&TypedFact]) -> TractResult<TVec<TypedFact>> {
        let mut shape: TVec<TDim> = inputs[0].shape.iter().cloned().collect();
        ensure!(shape.len() >= 2 && shape[shape.len() - 2] == self.n.into() && shape[shape.len() - 1] == 1.into());
        *shape.last_mut().expect("rank 2 or more") = 2.into();
        Ok(tvec!(f32::fact(shape)))
    }

    as_op!();
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The transform is the definition's, `X_f = Σ x_n e^{−2πi f n / N}`, row by row.
    #[test]
    fn each_row_is_transformed_by_the_definition() {
        let (rows, n) = (3, 10);
        let x: Vec<f32> = (0..rows * n).map(|i| ((i * 7) % 5) as f32 - 1.5).collect();
        let input = Tensor::from_shape(&[rows, n, 1], &x).unwrap();
        let out = RealDft::new(n).eval_out_of_plan(tvec!(input.into_tvalue())).unwrap().unwrap().remove(0);
        assert_eq!(out.shape(), &[rows, n, 2]);
        let view = out.to_plain_array_view::<f32>().unwrap();
        let got = view.as_slice().unwrap();
        for r in 0..rows {
            for f in 0..n {
                let (mut re, mut im) = (0.0f64, 0.0f64);
                for (k, v) in x[r * n..(r + 1) * n].iter().enumerate() {
                    let angle = -2.0 * std::f64::consts::PI * (f * k) as f64 / n as f64;
                    re += *v as f64 * angle.cos();
                    im += *v as f64 * angle.sin();
                }
                let at = (r * n + f) * 2;
                assert!((got[at] as f64 - re).abs() < 1e-4 && (got[at + 1] as f64 - im).abs() < 1e-4, "row {r} frequency {f}");
            }
        }
    }
}
