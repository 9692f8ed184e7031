//! [`EdgeShares`]: the camera head's histogram counts in one pass. The exporter writes each
//! pixel's share above each of a histogram's edges as ONNX's element-wise ops,
//! `clamp(−(v·s + o), 0, 1)` spelt `max(0 − max(v·s + o, −1), 0)`, over a `[rows, edges,
//! pixels]` tensor, then sums it over the pixels (export/src/spectrum/space.rs, `histogram`).
//! tract runs that as five passes over a tensor as many times the frames' size as there are
//! edges, about half of the shipped camera file's time (docs/benchmarks.md, "The camera's whole
//! window"). [`matched`] finds the pattern after decluttering, and [`super::fuse`] puts this op
//! in its place: it reads each row of pixels once, scales it, and sums every edge's shares in
//! registers. Each share is computed as tract computes it (a product, then a sum, then the
//! clamps), so only the order of the sum over the pixels changes.

use tract_core::internal::*;
use tract_core::ops::nn::{Reduce, Reducer};

use super::binary;

/// Lanes of the sum: eight partial sums per edge, added in a fixed order at the end.
const LANES: usize = 8;

/// `Σ_p clamp(−(x[r, p]·scale + offsets[e]), 0, 1)` for every row `r` and edge `e`, from `x`
/// `[…, 1, pixels]` to `[…, edges, 1]`.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct EdgeShares {
    scale: f32,
    offsets: Vec<f32>,
}

impl EdgeShares {
    fn run(&self, x: &Tensor) -> TractResult<Tensor> {
        let shape = x.shape();
        let pixels = *shape.last().context("a scalar input")?;
        let mut out_shape = shape.to_vec();
        let rank = out_shape.len();
        (out_shape[rank - 2], out_shape[rank - 1]) = (self.offsets.len(), 1);
        let view = x.to_plain_array_view::<f32>()?;
        let x = view.as_slice().context("a tensor in standard layout")?;
        let mut out = Vec::with_capacity(x.len() / pixels.max(1) * self.offsets.len());
        let mut scaled = vec![0f32; pixels];
        for row in x.chunks_exact(pixels) {
            for (s, v) in scaled.iter_mut().zip(row) {
                *s = v * self.scale;
            }
            out.extend(self.offsets.iter().map(|&o| sum_of_shares(&scaled, o)));
        }
        Tensor::from_shape(&out_shape, &out)
    }
}

/// `Σ_p clamp(−(scaled[p] + offset), 0, 1)`, each term exactly as tract's `max(0 − max(z, −1), 0)`
/// (no value is NaN: the runtime refuses such inputs).
fn sum_of_shares(scaled: &[f32], offset: f32) -> f32 {
    let share = |s: f32| {
        let z = s + offset;
        let below = if z > -1.0 { z } else { -1.0 };
        let above = 0.0 - below;
        if above > 0.0 {
            above
        } else {
            0.0
        }
    };
    let mut lanes = [0f32; LANES];
    let chunks = scaled.chunks_exact(LANES);
    let tail: f32 = chunks.remainder().iter().map(|&s| share(s)).sum();
    for chunk in chunks {
        for (lane, &s) in lanes.iter_mut().zip(chunk) {
            *lane += share(s);
        }
    }
    lanes.iter().sum::<f32>() + tail
}

// Equality compares the constants' values; a NaN among them only makes two ops unequal.
impl Eq for EdgeShares {}

impl Op for EdgeShares {
    fn name(&self) -> StaticName {
        "EdgeShares".into()
    }

    fn info(&self) -> TractResult<Vec<String>> {
        Ok(vec![format!("scale {}, {} edges", self.scale, self.offsets.len())])
    }

    op_as_typed_op!();
}

impl EvalOp for EdgeShares {
    op_out_of_plan!();

    fn eval(&self, _ctx: &EvalContext, inputs: TVec<TValue>) -> TractResult<TVec<TValue>> {
        Ok(tvec!(self.run(&inputs[0])?.into_tvalue()))
    }
}

impl TypedOp for EdgeShares {
    fn output_facts(&self, inputs: &[&TypedFact]) -> TractResult<TVec<TypedFact>> {
        let mut shape = inputs[0].shape.to_tvec();
        let rank = shape.len();
        (shape[rank - 2], shape[rank - 1]) = (self.offsets.len().to_dim(), 1.to_dim());
        Ok(tvec!(f32::fact(shape)))
    }

    as_op!();
}

/// Node `id` as an [`EdgeShares`] and the input it reads, if it sums edge shares. The pattern,
/// from the sum back: `Reduce<Sum>` over the last axis of
/// `Max(·, 0)` of `Sub(0, ·)` of `Max(·, −1)` of `Add(·, offsets [edges, 1])` of
/// `Mul(x […, 1, pixels], scale)`, each step read by the next alone.
pub(super) fn matched(model: &TypedModel, id: usize) -> TractResult<Option<(EdgeShares, OutletId)>> {
    let node = model.node(id);
    let Some(reduce) = node.op_as::<Reduce>() else { return Ok(None) };
    let rank = model.outlet_fact(node.inputs[0])?.rank();
    if reduce.reducer != Reducer::Sum || *reduce.axes != [rank - 1] {
        return Ok(None);
    }
    let walk = |outlet: OutletId, name: &str| binary(model, outlet, name, true);
    let Some((share, zero, _)) = walk(node.inputs[0], "Max")? else { return Ok(None) };
    let Some((below, zero_before, true)) = walk(share, "Sub")? else { return Ok(None) };
    let Some((z, minus_one, _)) = walk(below, "Max")? else { return Ok(None) };
    let Some((scaled, offsets, _)) = walk(z, "Add")? else { return Ok(None) };
    let Some((x, scale, _)) = walk(scaled, "Mul")? else { return Ok(None) };
    let (x_fact, z_fact) = (model.outlet_fact(x)?, model.outlet_fact(z)?);
    let (Some(x_shape), Some(z_shape)) = (x_fact.shape.as_concrete(), z_fact.shape.as_concrete()) else { return Ok(None) };
    let is = |t: &Tensor, v: f32| t.len() == 1 && t.cast_to_scalar::<f32>().is_ok_and(|s| s == v);
    let fits = x_fact.datum_type == f32::datum_type()
        && x_shape.len() == rank
        && x_shape[rank - 2] == 1
        && x_shape[rank - 1] == z_shape[rank - 1]
        && x_shape[..rank - 2] == z_shape[..rank - 2]
        && offsets.datum_type() == f32::datum_type()
        && offsets.len() == z_shape[rank - 2]
        && offsets.shape().last() == Some(&1)
        && scale.datum_type() == f32::datum_type()
        && scale.len() == 1
        && is(&zero, 0.0)
        && is(&zero_before, 0.0)
        && is(&minus_one, -1.0);
    if !fits {
        return Ok(None);
    }
    let offsets = offsets.to_plain_array_view::<f32>()?.iter().copied().collect();
    let op = EdgeShares { scale: scale.cast_to_scalar::<f32>()?, offsets };
    Ok(Some((op, x)))
}
