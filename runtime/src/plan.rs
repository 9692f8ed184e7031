//! [`Plan`]: an optimised tract plan with its run states kept for reuse. Spawning a fresh state
//! per run (what `SimplePlan::run` does) cost about 15 µs of the iCub model's 580 µs at batch 1.

use std::panic::AssertUnwindSafe;
use std::sync::Mutex;

use tract_core::internal::{ensure, format_err};
use tract_core::optim::Optimizer;
use tract_core::prelude::*;

use crate::error::{catch_panic, tract_error};
use crate::{Error, Result};

/// tract's decluttering, one round: each of its passes run until it has nothing more to change,
/// once, in tract's order. tract's own (`TypedModel::declutter`) repeats the round until a whole
/// round changes nothing: on the exporter's graphs the second round changes a few `Add`, `Mul` and
/// reshapes, the plans run alike (docs/benchmarks.md, step 20), and the rounds after the first cost a
/// third of the time, 4–5 ms of the first call's ~21 ms. Then the runtime's own fusions replace
/// what tract runs slowly (the `fusions` module).
pub fn declutter(model: &mut TypedModel) -> TractResult<()> {
    tract_declutter(model)?;
    crate::fusions::fuse(model)?;
    Ok(())
}

/// tract's own decluttering, one round ([`declutter`] without the runtime's fusions).
pub(crate) fn tract_declutter(model: &mut TypedModel) -> TractResult<()> {
    let optimizer = Optimizer::declutter();
    let mut session = optimizer.session();
    model.compact()?;
    // A pass that changed the model left it compacted (`run_one_pass_outer` compacts after each
    // sweep that applied a patch); one that changed nothing needs no compaction.
    for pass in optimizer.passes.clone().iter_mut() {
        session.run_one_pass_outer(0, pass.as_mut(), model)?;
    }
    Ok(())
}

/// `model` decluttered ([`declutter`]), its gathers checked ([`check_gathers`]) and optimised by
/// tract (its code generation, to tract's fixed point): what the runtime plans run.
pub(crate) fn optimised(mut model: TypedModel, index_bounds: &[(&str, usize)]) -> TractResult<TypedModel> {
    declutter(&mut model)?;
    check_gathers(&model, index_bounds)?;
    model.optimize()?;
    Ok(model)
}

/// tract's `Gather` indexes without a check, so a file whose indices point outside their axis
/// would panic at run time. After decluttering has folded what is constant, every gather's
/// indices are either constants, checked here against the axis, or one of the model's inputs
/// with a known bound (`index_bounds`: the input's name and the largest value the runtime feeds
/// it, plus one), checked against it. Anything else is refused.
fn check_gathers(model: &TypedModel, index_bounds: &[(&str, usize)]) -> TractResult<()> {
    for node in model.nodes() {
        let Some(gather) = node.op_as::<tract_core::ops::array::Gather>() else { continue };
        let (data, indices) = (model.outlet_fact(node.inputs[0])?, model.outlet_fact(node.inputs[1])?);
        let len = data
            .shape
            .get(gather.axis)
            .and_then(|d| d.to_i64().ok())
            .ok_or_else(|| format_err!("{}: an axis of unknown length", node.name))?;
        match &indices.konst {
            Some(k) => {
                let k = k.cast_to::<i64>()?;
                let bad = k.to_plain_array_view::<i64>()?.iter().copied().find(|i| !(-len..len).contains(i));
                ensure!(bad.is_none(), "{}: index {} of an axis of length {len}", node.name, bad.unwrap_or_default());
            }
            None => {
                let source = &model.nodes()[node.inputs[1].node];
                let bound = index_bounds.iter().find(|(name, _)| *name == source.name).map(|b| b.1);
                let bound = bound.ok_or_else(|| format_err!("{}: indices computed while the model runs", node.name))?;
                ensure!(bound as i64 <= len, "{}: indices up to {} of an axis of length {len}", node.name, bound - 1);
            }
        }
    }
    Ok(())
}

pub(crate) struct Plan {
    plan: Arc<TypedRunnableModel>,
    /// The graph's name of each output, as the file's refusals give it.
    outputs: Vec<String>,
    /// States not in use; a caller running concurrently with another spawns its own.
    idle: Mutex<Vec<TypedSimpleState>>,
    /// The values of the plan's largest tensor, its input and outputs included: read at every
    /// batch's run (`Classifier::windows_per_run`), so counted once, here.
    largest_tensor: usize,
}

impl Plan {
    /// `plan`, whose outputs are the tensors named `outputs`.
    pub(crate) fn new(plan: Arc<TypedRunnableModel>, outputs: Vec<String>) -> Self {
        let largest_tensor = plan
            .model()
            .nodes()
            .iter()
            .flat_map(|n| &n.outputs)
            .filter_map(|o| o.fact.shape.as_concrete().map(|s| s.iter().product()))
            .max()
            .unwrap_or(0);
        Self { plan, outputs, idle: Mutex::new(Vec::new()), largest_tensor }
    }

    /// The names of `model`'s outputs, as the wiring labelled them.
    pub(crate) fn output_names(model: &TypedModel) -> Vec<String> {
        model.output_outlets().unwrap_or_default().iter().map(|o| model.outlet_label(*o).unwrap_or("?").to_string()).collect()
    }

    /// Output `i` of this plan's `outputs`, which must hold `len` f32 values.
    pub(crate) fn output(&self, outputs: &[TValue], i: usize, len: usize) -> Result<Vec<f32>> {
        let name = self.outputs.get(i).map_or("?", String::as_str);
        let values = outputs.get(i).ok_or_else(|| Error::Tract(format!("the plan has no output `{name}`")))?;
        if values.datum_type() != f32::datum_type() {
            return Err(Error::Tract(format!("output `{name}` holds {:?}, not the f32 the header implies", values.datum_type())));
        }
        let values: Vec<f32> = values.to_plain_array_view::<f32>().map_err(tract_error)?.iter().copied().collect();
        if values.len() != len {
            return Err(Error::Tract(format!("output `{name}` has {} values, not the {len} the header implies", values.len())));
        }
        Ok(values)
    }

    /// The values of the plan's largest tensor, its input and outputs included.
    pub(crate) fn largest_tensor(&self) -> usize {
        self.largest_tensor
    }

    /// Runs the plan. A state that panicked is dropped, not reused.
    pub(crate) fn run(&self, inputs: TVec<TValue>) -> Result<TVec<TValue>> {
        let idle = self.idle.lock().unwrap_or_else(|p| p.into_inner()).pop();
        let mut state = match idle {
            Some(state) => state,
            None => self.plan.spawn().map_err(tract_error)?,
        };
        let outputs = catch_panic(AssertUnwindSafe(|| state.run(inputs)))?.map_err(tract_error)?;
        self.idle.lock().unwrap_or_else(|p| p.into_inner()).push(state);
        Ok(outputs)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A reused state gives the same answer as a fresh one, run after run.
    #[test]
    fn a_reused_state_runs_like_a_fresh_one() {
        let mut model = TypedModel::default();
        let x = model.add_source("x", f32::fact([3])).unwrap();
        let two = model.add_const("two", tensor1(&[2f32, 2.0, 2.0])).unwrap();
        let y = model.wire_node("y", tract_core::ops::math::mul(), &[x, two]).unwrap();
        model.select_output_outlets(&y).unwrap();
        let plan = Plan::new(model.into_runnable().unwrap(), vec!["y".into()]);
        for k in 0..3 {
            let v = k as f32;
            let out = plan.run(tvec!(tensor1(&[v, 1.0, -v]).into())).unwrap();
            assert_eq!(out[0].to_plain_array_view::<f32>().unwrap().iter().copied().collect::<Vec<_>>(), vec![2.0 * v, 2.0, -2.0 * v]);
        }
        assert_eq!(plan.idle.lock().unwrap().len(), 1, "one state, reused");
    }
}
