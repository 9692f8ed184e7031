//! The runtime's own fusions: patterns of the exporter's graph that tract runs as several passes
//! over large tensors, each replaced after decluttering by one op that reads its input once and
//! computes every value as tract would (the same operations in the same order; only a sum's
//! order may change, where an op says so).

mod edge_shares;
mod standardise;

use tract_core::internal::*;
use tract_core::ops::binary::TypedBinOp;
use tract_core::ops::element_wise::ElementWiseOp;
use tract_core::ops::math::Recip;

/// Puts the runtime's fused ops in place of their patterns in `model` (decluttered), and returns
/// how many: each node that ends a pattern takes the fused op and reads the pattern's input; the
/// nodes before it drop out.
pub(crate) fn fuse(model: &mut TypedModel) -> TractResult<usize> {
    let mut fused = 0;
    for id in model.eval_order()? {
        let (op, input): (Box<dyn TypedOp>, OutletId) = if let Some((op, x)) = edge_shares::matched(model, id)? {
            (Box::new(op), x)
        } else if let Some((op, x)) = standardise::matched(model, id)? {
            (Box::new(op), x)
        } else {
            continue;
        };
        model.add_edge(input, InletId::new(id, 0))?;
        for (slot, old) in model.node(id).inputs.clone().into_iter().enumerate().skip(1) {
            model.node_mut(old.node).outputs[old.slot].successors.retain(|s| *s != InletId::new(id, slot));
        }
        let node = model.node_mut(id);
        node.inputs.truncate(1);
        node.op = op;
        fused += 1;
    }
    if fused > 0 {
        model.compact()?;
    }
    Ok(fused)
}

/// The wired input of `outlet`'s node, its constant and whether the constant comes first, if the
/// node is the element-wise `name` of one wire and one constant; `inner`: inside a pattern,
/// where nothing but the pattern's next node may read it.
fn binary(model: &TypedModel, outlet: OutletId, name: &str, inner: bool) -> TractResult<Option<(OutletId, Arc<Tensor>, bool)>> {
    let node = model.node(outlet.node);
    let Some(op) = node.op_as::<TypedBinOp>() else { return Ok(None) };
    if op.0.name() != name || node.inputs.len() != 2 || (inner && model.outlet_successors(outlet).len() != 1) {
        return Ok(None);
    }
    let konst = |i: usize| constant(model, node.inputs[i]);
    Ok(match (konst(0)?, konst(1)?) {
        (None, Some(k)) => Some((node.inputs[0], k, false)),
        (Some(k), None) => Some((node.inputs[1], k, true)),
        _ => None,
    })
}

/// The value of `outlet` if it is a constant, or the reciprocal of one: tract's decluttering
/// writes a `Div` by a constant as a `Mul` by a `Recip` it leaves unfolded. The reciprocal is
/// computed as tract's `Recip` computes it (`f32::recip`).
fn constant(model: &TypedModel, outlet: OutletId) -> TractResult<Option<Arc<Tensor>>> {
    if let Some(k) = &model.outlet_fact(outlet)?.konst {
        return Ok(Some(k.clone()));
    }
    let node = model.node(outlet.node);
    let Some(op) = node.op_as::<ElementWiseOp>() else { return Ok(None) };
    let Some(k) = (op.0.is::<Recip>()).then(|| model.outlet_fact(node.inputs[0]).map(|f| f.konst.clone())).transpose()?.flatten() else {
        return Ok(None);
    };
    if k.datum_type() != f32::datum_type() {
        return Ok(None);
    }
    let mut r = k.into_tensor();
    r.try_as_plain_ram_mut()?.as_slice_mut::<f32>()?.iter_mut().for_each(|v| *v = v.recip());
    Ok(Some(r.into_arc_tensor()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shipped camera model, with and without the runtime's fusions, on its shipped touch:
    /// both fusions apply (the histogram's sums and the head's standardisation), and the logits
    /// agree within 1e-5 of the largest (only the order of the histogram's sums changed).
    #[test]
    fn the_fused_camera_plan_computes_what_tracts_own_plan_computes() {
        let shipped = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shipped");
        let classifier = crate::Classifier::load(shipped.join("physiclear.onnx")).unwrap();
        let (shape, values) = crate::read_npy(&shipped.join("physiclear-touch.npy")).unwrap();
        let input = Tensor::from_shape(&[[1].as_slice(), &shape].concat(), &values).unwrap();
        let logits = |fused: bool| {
            let mut model = classifier.tract_model(1).unwrap();
            crate::plan::tract_declutter(&mut model).unwrap();
            if fused {
                assert_eq!(fuse(&mut model).unwrap(), 2, "an EdgeShares and a Standardise");
                assert!(model.nodes().iter().any(|n| n.op_is::<edge_shares::EdgeShares>()));
                assert!(model.nodes().iter().any(|n| n.op_is::<standardise::Standardise>()));
            }
            model.optimize().unwrap();
            let out = model.into_runnable().unwrap().run(tvec!(input.clone().into_tvalue())).unwrap();
            out[0].to_plain_array_view::<f32>().unwrap().iter().copied().collect::<Vec<f32>>()
        };
        let (fused, tract) = (logits(true), logits(false));
        let largest = tract.iter().fold(0f32, |m, v| m.max(v.abs()));
        let worst = fused.iter().zip(&tract).map(|(a, b)| (a - b).abs()).fold(0f32, f32::max);
        assert!(worst <= 1e-5 * largest, "logits differ by {worst} (largest {largest})");
    }
}
