//! [`Standardise`]: `(x − mean) ⊙ scale` with constants as large as a trailing part of `x` (a
//! frame's, or a row's, mean and 1 / std per value: tract's decluttering turns the exporter's
//! `Div` by a constant into a `Mul` by its reciprocal). tract broadcasts such constants
//! through its generic path, one slow pass each (the camera head's standardisation:
//! docs/benchmarks.md, "The camera's whole window"). This op walks
//! `x` once, the constants repeating along it; each value gets the same two operations tract
//! would give it, so the same bits.

use tract_core::internal::*;

use super::binary;

/// `(x − mean) · scale`, `mean` and `scale` repeating along `x`.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Standardise {
    mean: Vec<f32>,
    scale: Vec<f32>,
}

// Equality compares the constants' values; a NaN among them only makes two ops unequal.
impl Eq for Standardise {}

impl Standardise {
    fn run(&self, x: &Tensor) -> TractResult<Tensor> {
        let view = x.to_plain_array_view::<f32>()?;
        let x = view.as_slice().context("a tensor in standard layout")?;
        let mut out = Vec::with_capacity(x.len());
        for chunk in x.chunks_exact(self.mean.len()) {
            out.extend(chunk.iter().zip(&self.mean).zip(&self.scale).map(|((v, m), s)| (v - m) * s));
        }
        Tensor::from_shape(view.shape(), &out)
    }
}

impl Op for Standardise {
    fn name(&self) -> StaticName {
        "Standardise".into()
    }

    fn info(&self) -> TractResult<Vec<String>> {
        Ok(vec![format!("{} values", self.mean.len())])
    }

    op_as_typed_op!();
}

impl EvalOp for Standardise {
    op_out_of_plan!();

    fn eval(&self, _ctx: &EvalContext, inputs: TVec<TValue>) -> TractResult<TVec<TValue>> {
        Ok(tvec!(self.run(&inputs[0])?.into_tvalue()))
    }
}

impl TypedOp for Standardise {
    fn output_facts(&self, inputs: &[&TypedFact]) -> TractResult<TVec<TypedFact>> {
        Ok(tvec!(f32::fact(inputs[0].shape.clone())))
    }

    as_op!();
}

/// Node `id` as a [`Standardise`] and the input it reads: a `Mul` by a constant of a
/// `Sub` of a constant (read by nothing else), both constants shaped as a trailing part of the
/// input, which is f32, of a fixed shape and at least as large as them.
pub(super) fn matched(model: &TypedModel, id: usize) -> TractResult<Option<(Standardise, OutletId)>> {
    let outlet = OutletId::new(id, 0);
    let Some((centred, scale, false)) = binary(model, outlet, "Mul", false)? else { return Ok(None) };
    let Some((x, mean, false)) = binary(model, centred, "Sub", true)? else { return Ok(None) };
    let fact = model.outlet_fact(x)?;
    let Some(shape) = fact.shape.as_concrete() else { return Ok(None) };
    let trailing = |c: &Tensor| {
        let dims: Vec<usize> = c.shape().iter().copied().skip_while(|d| *d == 1).collect();
        c.datum_type() == f32::datum_type() && c.rank() <= shape.len() && shape.ends_with(&dims) && !dims.is_empty()
    };
    if fact.datum_type != f32::datum_type() || !trailing(&mean) || !trailing(&scale) || mean.shape() != scale.shape() {
        return Ok(None);
    }
    let values = |c: &Tensor| -> TractResult<Vec<f32>> { Ok(c.to_plain_array_view::<f32>()?.iter().copied().collect()) };
    Ok(Some((Standardise { mean: values(&mean)?, scale: values(&scale)? }, x)))
}
