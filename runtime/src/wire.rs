//! From the exporter's ONNX nodes to a tract [`TypedModel`] with fixed input shapes, built from
//! tract-core's operators directly, as tract's ONNX loader would after its type analysis. The
//! runtime reads the operators `pvt3 export` writes and no others; a file with another one is
//! refused by name. Shapes are fixed when a plan is built, so shape arithmetic (`Shape`,
//! `Slice` and `Concat` of shapes) becomes constants here, and `Reshape` and `Expand` read theirs.
//!
//! [`typed_model`] builds the part of the graph between given tensors: the whole model from its
//! input, or one stage of it from a seam (`pvt3_format::TOKEN_FRAMES` …), so that streaming and
//! whole-window classification run the same nodes of the one file.

use std::collections::{HashMap, HashSet};

use tract_core::internal::*;
use tract_core::ops::array::{Gather, MultiBroadcastTo, Slice, TypedConcat};
use tract_core::ops::change_axes::{perm_to_ops, to_axis_ops_with_onnx_rules, wire_with_rank_broadcast};
use tract_core::ops::einsum::EinSum;
use tract_core::ops::math;
use tract_core::ops::nn::{Reduce, Reducer, Softmax};

use pvt3_format::onnx::{GraphProto as Graph, NodeProto as Node, Op};
use pvt3_format::Budget;

/// The model computing `outputs` from the tensors named in `sources`, each with its fixed fact,
/// for `windows` windows: every tensor it computes is within `budget` for that many windows
/// ([`Budget::admit`]), checked as each node is wired, before anything computes it. An error
/// names what is missing, not understood or too large.
pub(crate) fn typed_model(
    graph: &Graph,
    sources: &[(&str, TypedFact)],
    outputs: &[&str],
    budget: Budget,
    windows: usize,
) -> Result<TypedModel, String> {
    let produced = |name: &str| graph.node.iter().any(|n| n.output.iter().any(|o| o == name));
    let read = |name: &str| graph.node.iter().any(|n| n.input.iter().any(|i| i == name));
    let unknown = outputs.iter().copied().find(|o| !produced(o)).or_else(|| sources.iter().map(|s| s.0).find(|s| !produced(s) && !read(s)));
    if let Some(name) = unknown {
        return Err(format!("no tensor named `{name}` (exported by an older pvt3?)"));
    }
    let seams: HashSet<&str> = sources.iter().map(|s| s.0).collect();
    // ONNX lists nodes in topological order, so one backward pass finds every node needed.
    let mut needed: HashSet<&str> = outputs.iter().copied().collect();
    let mut keep = vec![false; graph.node.len()];
    for (i, node) in graph.node.iter().enumerate().rev() {
        if node.output.iter().any(|o| needed.contains(o.as_str())) && !node.output.iter().any(|o| seams.contains(o.as_str())) {
            keep[i] = true;
            needed.extend(node.input.iter().map(String::as_str).filter(|n| !n.is_empty() && !seams.contains(n)));
        }
    }
    let mut b = Builder { model: TypedModel::default(), wires: HashMap::new(), graph, budget, windows };
    for (name, fact) in sources {
        let source = b.model.add_source(*name, fact.clone()).map_err(|e| e.to_string())?;
        b.wires.insert(name.to_string(), source);
    }
    b.admitted_since(0)
        .map_err(|e| format!("the input {}: {e}", sources.iter().map(|s| format!("`{}`", s.0)).collect::<Vec<_>>().join(", ")))?;
    for node in graph.node.iter().zip(&keep).filter(|(_, k)| **k).map(|(n, _)| n) {
        let wired = b.model.nodes().len();
        let out = b.node(node).and_then(|out| b.admitted_since(wired).map(|_| out));
        let out = out.map_err(|e| format!("{} ({}): {e:#}", node.name, node.op_type))?;
        let name = node.output.first().ok_or_else(|| format!("{}: a node without output", node.name))?;
        b.wires.insert(name.clone(), out);
    }
    let outlets = outputs.iter().map(|o| b.input(o)).collect::<TractResult<Vec<_>>>().map_err(|e| e.to_string())?;
    b.model.select_output_outlets(&outlets).map_err(|e| e.to_string())?;
    // Each output labelled with its tensor's name, which a plan's refusals then give.
    for (outlet, name) in outlets.iter().zip(outputs) {
        b.model.set_outlet_label(*outlet, name.to_string()).map_err(|e| e.to_string())?;
    }
    Ok(b.model)
}

struct Builder<'a> {
    model: TypedModel,
    /// The outlet computing each tensor wired so far.
    wires: HashMap<String, OutletId>,
    graph: &'a Graph,
    /// What any tensor may hold for one window, and how many windows the model holds.
    budget: Budget,
    windows: usize,
}

impl Builder<'_> {
    /// The outlet of tensor `name`: wired already, or an initializer made a constant now.
    fn input(&mut self, name: &str) -> TractResult<OutletId> {
        if let Some(o) = self.wires.get(name) {
            return Ok(*o);
        }
        let init = self.graph.initializer.iter().find(|t| t.name == name).ok_or_else(|| format_err!("no tensor named `{name}`"))?;
        let tensor = crate::onnx::to_tensor(init, self.budget).map_err(|e| format_err!("{e}"))?;
        let o = self.model.add_const(name, tensor)?;
        self.wires.insert(name.into(), o);
        Ok(o)
    }

    /// Checks that `shape` is within the budget for the model's windows.
    fn admit(&self, shape: &[usize]) -> TractResult<()> {
        self.budget.admit(shape, self.windows).map(drop).map_err(|why| format_err!("a tensor {why}"))
    }

    /// Checks every output of the nodes wired from node `first` on ([`Self::admit`]).
    fn admitted_since(&self, first: usize) -> TractResult<()> {
        for node in &self.model.nodes()[first..] {
            for output in &node.outputs {
                let shape = output.fact.shape.as_concrete().ok_or_else(|| format_err!("a shape that is not fixed"))?;
                self.admit(shape)?;
            }
        }
        Ok(())
    }

    fn fact(&self, o: OutletId) -> TractResult<TypedFact> {
        Ok(self.model.outlet_fact(o)?.clone())
    }

    /// The fixed shape of `o`.
    fn shape(&self, o: OutletId) -> TractResult<Vec<usize>> {
        Ok(self.fact(o)?.shape.as_concrete().ok_or_else(|| format_err!("a shape that is not fixed"))?.to_vec())
    }

    /// The value of `o` as integers: it must be known when the plan is built (a shape, axes).
    fn konst(&self, o: OutletId) -> TractResult<Vec<i64>> {
        let k = self.fact(o)?.konst.ok_or_else(|| format_err!("a shape or axes input that is not constant"))?;
        Ok(k.cast_to::<i64>()?.to_plain_array_view::<i64>()?.iter().copied().collect())
    }

    /// Axis `a` of a tensor of `rank` axes, negative ones counted from the end.
    fn axis(a: i64, rank: usize) -> TractResult<usize> {
        let r = rank as i64;
        ensure!((-r..r).contains(&a), "axis {a} of a tensor of rank {rank}");
        Ok(a.rem_euclid(r) as usize)
    }

    /// Wires `op`; an op whose inputs are all constants is computed here and becomes a constant
    /// itself, so that what feeds a gather's indices is known (and checked) when it is wired.
    fn wire(&mut self, name: String, op: impl Into<Box<dyn TypedOp>>, inputs: &[OutletId]) -> TractResult<OutletId> {
        // Wired first: tract checks the inputs' shapes against the op before anything runs it,
        // and the output's size is checked before anything computes it.
        let o = self.model.wire_node(name.clone(), op, inputs)?[0];
        self.admit(&self.shape(o)?)?;
        let konsts: Option<TVec<TValue>> = inputs.iter().map(|o| Some(self.fact(*o).ok()?.konst?.into_tvalue())).collect();
        if let Some(values) = konsts.filter(|_| !inputs.is_empty()) {
            if let Some(mut out) = self.model.node(o.node).op.eval_out_of_plan(values)? {
                ensure!(out.len() == 1, "an op of {} outputs", out.len());
                return self.model.add_const(format!("{name}.value"), out.remove(0).into_tensor());
            }
        }
        Ok(o)
    }

    fn node(&mut self, node: &Node) -> TractResult<OutletId> {
        ensure!(node.domain.is_empty() || node.domain == "ai.onnx", "operator domain `{}`", node.domain);
        let inputs = node.input.iter().filter(|i| !i.is_empty()).map(|i| self.input(i)).collect::<TractResult<Vec<_>>>()?;
        let arity = |n: std::ops::RangeInclusive<usize>| -> TractResult<()> {
            ensure!(n.contains(&inputs.len()), "{} inputs", inputs.len());
            Ok(())
        };
        let name = node.name.clone();
        let x = *inputs.first().ok_or_else(|| format_err!("no input"))?;
        let rank = self.fact(x)?.rank();
        let op = node.op().ok_or_else(|| format_err!("operator {}, which pvt3 does not export", node.op_type))?;
        // Every operator the exporter writes, and no other (`Op` is exhaustive).
        match op {
            Op::Identity => Ok(x),
            Op::Add | Op::Sub | Op::Mul | Op::Div | Op::Max => {
                arity(2..=2)?;
                let op = match op {
                    Op::Add => math::add(),
                    Op::Sub => math::sub(),
                    Op::Mul => math::mul(),
                    Op::Div => math::div(),
                    _ => math::max(),
                };
                Ok(wire_with_rank_broadcast(name, &mut self.model, op, &inputs)?[0])
            }
            Op::Exp | Op::Sqrt | Op::Erf | Op::Log => {
                arity(1..=1)?;
                let op = match op {
                    Op::Exp => math::exp(),
                    Op::Sqrt => math::sqrt(),
                    Op::Log => math::ln(),
                    _ => math::erf(),
                };
                self.wire(name, op, &inputs)
            }
            Op::Dft => {
                // Opset 17, as the exporter writes it (the spectral head): a forward, two-sided
                // transform of a real signal `[…, n, 1]` along its frames `n`, to `[…, n, 2]`.
                arity(1..=1)?;
                ensure!(node.int("inverse", 0) == 0 && node.int("onesided", 0) == 0, "an inverse or one-sided transform");
                let shape = self.shape(x)?;
                ensure!(shape.last() == Some(&1), "a complex input");
                let axis = Self::axis(node.int("axis", 1), rank)?;
                ensure!(axis + 2 == rank, "a transform along another axis than the next-to-last");
                self.wire(name, crate::real_dft::RealDft::new(shape[axis]), &[x])
            }
            Op::MatMul => {
                arity(2..=2)?;
                self.matmul(name, &inputs, rank)
            }
            Op::Transpose => {
                arity(1..=1)?;
                self.transpose(node, name, &inputs, rank)
            }
            Op::Reshape => {
                arity(2..=2)?;
                self.reshape(node, name, &inputs)
            }
            Op::Expand => {
                arity(2..=2)?;
                let to = self.konst(inputs[1])?;
                ensure!(to.iter().all(|d| *d >= 0), "a shape {to:?}");
                self.admit(&to.iter().map(|d| *d as usize).collect::<Vec<_>>())?;
                let to: TVec<TDim> = to.iter().map(|d| d.to_dim()).collect();
                let from: TVec<TDim> = self.shape(x)?.iter().map(|d| d.to_dim()).collect();
                let dims = tract_core::broadcast::multi_broadcast(&[&*from, &*to])?;
                self.wire(name, MultiBroadcastTo::new(dims.into()), &[x])
            }
            Op::Gather => {
                arity(2..=2)?;
                self.gather(node, name, &inputs, rank)
            }
            Op::Concat => self.wire(name, TypedConcat::new(Self::axis(node.int("axis", 0), rank)?), &inputs),
            Op::Shape => {
                arity(1..=1)?;
                ensure!(!node.has("start") && !node.has("end"), "start or end");
                let shape: Vec<i64> = self.shape(x)?.iter().map(|d| *d as i64).collect();
                Ok(self.model.add_const(name, tensor1(&shape))?)
            }
            Op::Slice => {
                arity(3..=5)?;
                self.slice(name, &inputs, rank)
            }
            Op::ReduceSum | Op::ReduceMean => {
                arity(1..=2)?;
                self.reduce(node, name, &inputs, rank, op)
            }
            Op::Softmax => {
                arity(1..=1)?;
                let axis = Self::axis(node.int("axis", -1), rank)?;
                self.wire(name, Softmax { axes: tvec!(axis), ..Softmax::default() }, &[x])
            }
            Op::LayerNormalization => {
                arity(2..=3)?;
                self.layer_norm(node, &inputs, rank)
            }
        }
    }

    /// `MatMul` as tract's einsum, its operands' shapes checked.
    fn matmul(&mut self, name: String, inputs: &[OutletId], rank: usize) -> TractResult<OutletId> {
        let x = inputs[0];
        let (a, b) = (rank, self.fact(inputs[1])?.rank());
        ensure!(a >= 2 && b >= 2, "a product of vectors");
        // tract's einsum trusts its operands' shapes: the summed axes must agree, and the
        // leading ones be equal or 1, or it would index out of bounds as it runs.
        let (sa, sb) = (self.shape(x)?, self.shape(inputs[1])?);
        ensure!(sa[a - 1] == sb[b - 2], "a product of {sa:?} and {sb:?}");
        let lead = |s: &[usize], r: usize, i: usize| if i + r >= a.max(b) { s[i + r - a.max(b)] } else { 1 };
        for i in 0..a.max(b) - 2 {
            let (da, db) = (lead(&sa, a, i), lead(&sb, b, i));
            ensure!(da == db || da == 1 || db == 1, "a product of {sa:?} and {sb:?}");
        }
        let c = a.max(b);
        let prefix = |skip: usize| ('a'..).take(c - 2).skip(skip).collect::<String>();
        let expr = format!("{}mk,{}kn->{}mn", prefix(c - a), prefix(c - b), prefix(0));
        let dt = self.fact(x)?.datum_type;
        self.wire(name, EinSum { axes: expr.parse()?, operating_dt: dt, q_params: None }, inputs)
    }

    /// `Transpose` as tract's axis moves.
    fn transpose(&mut self, node: &Node, name: String, inputs: &[OutletId], rank: usize) -> TractResult<OutletId> {
        let x = inputs[0];
        let perm: Vec<usize> = match node.ints("perm") {
            Some(p) => p.iter().map(|a| Self::axis(*a, rank)).collect::<TractResult<_>>()?,
            None => (0..rank).rev().collect(),
        };
        ensure!(perm.len() == rank && (0..rank).all(|a| perm.contains(&a)), "permutation {perm:?} of rank {rank}");
        let mut wire = x;
        for (i, op) in perm_to_ops(&perm).into_iter().enumerate() {
            wire = self.wire(format!("{name}.{i}"), op, &[wire])?;
        }
        Ok(wire)
    }

    /// `Reshape` to a constant shape, as tract's axis operations by ONNX's rules.
    fn reshape(&mut self, node: &Node, name: String, inputs: &[OutletId]) -> TractResult<OutletId> {
        let x = inputs[0];
        ensure!(node.int("allowzero", 0) == 0, "allowzero");
        let from: TVec<TDim> = self.shape(x)?.iter().map(|d| d.to_dim()).collect();
        let to = self.konst(inputs[1])?;
        ensure!(to.iter().all(|d| *d >= -1) && to.iter().filter(|d| **d == -1).count() <= 1, "a shape {to:?}");
        self.admit(&to.iter().map(|d| (*d).max(0) as usize).collect::<Vec<_>>())?;
        let to: TVec<TDim> = to.iter().map(|d| d.to_dim()).collect();
        let mut wire = x;
        for (i, op) in to_axis_ops_with_onnx_rules(&from, &to, false)?.into_iter().enumerate() {
            wire = self.wire(format!("{name}.{i}"), op, &[wire])?;
        }
        Ok(wire)
    }

    /// `Gather` along an axis, its constant indices checked here.
    fn gather(&mut self, node: &Node, name: String, inputs: &[OutletId], rank: usize) -> TractResult<OutletId> {
        let x = inputs[0];
        ensure!(self.fact(inputs[1])?.datum_type == i64::datum_type(), "indices that are not int64");
        let axis = Self::axis(node.int("axis", 0), rank)?;
        // tract's gather indexes unchecked: constant indices are checked here, and the
        // only others a file may have are an input's (a stage's `token_index`), which the
        // plan checks against the bound the runtime feeds it (`plan::check_gathers`).
        let d = self.shape(x)?[axis] as i64;
        if self.fact(inputs[1])?.konst.is_some() {
            let bad = self.konst(inputs[1])?.into_iter().find(|i| !(-d..d).contains(i));
            ensure!(bad.is_none(), "index {} of an axis of length {d}", bad.unwrap_or_default());
        } else {
            ensure!(self.model.node(inputs[1].node).op_is::<tract_core::ops::source::TypedSource>(), "indices computed from other tensors");
        }
        self.wire(name, Gather::new(axis), inputs)
    }

    /// `Slice` by constant starts, ends and axes (steps of 1), one tract slice an axis.
    fn slice(&mut self, name: String, inputs: &[OutletId], rank: usize) -> TractResult<OutletId> {
        let x = inputs[0];
        let (starts, ends) = (self.konst(inputs[1])?, self.konst(inputs[2])?);
        let axes = match inputs.get(3) {
            Some(a) => self.konst(*a)?,
            None => (0..starts.len() as i64).collect(),
        };
        if let Some(steps) = inputs.get(4) {
            ensure!(self.konst(*steps)?.iter().all(|s| *s == 1), "steps other than 1");
        }
        ensure!(starts.len() == ends.len() && ends.len() == axes.len(), "starts, ends and axes of different lengths");
        let shape = self.shape(x)?;
        let mut wire = x;
        for (i, ((s, e), a)) in starts.iter().zip(&ends).zip(&axes).enumerate() {
            let axis = Self::axis(*a, rank)?;
            let d = shape[axis] as i64;
            let clamp = |v: i64| (if v < 0 { v + d } else { v }).clamp(0, d) as usize;
            let (start, end) = (clamp(*s), clamp(*e));
            wire = self.wire(format!("{name}.{i}"), Slice::new(axis, start, end.max(start)), &[wire])?;
        }
        Ok(wire)
    }

    /// `ReduceSum` or `ReduceMean` (`op`) over constant axes, their axes kept or removed.
    fn reduce(&mut self, node: &Node, name: String, inputs: &[OutletId], rank: usize, op: Op) -> TractResult<OutletId> {
        let x = inputs[0];
        let axes = match (inputs.get(1), node.ints("axes")) {
            (Some(a), _) => self.konst(*a)?,
            (None, Some(a)) => a.to_vec(),
            (None, None) => (0..rank as i64).collect(),
        };
        let mut axes = axes.iter().map(|a| Self::axis(*a, rank)).collect::<TractResult<Vec<_>>>()?;
        axes.sort();
        axes.dedup();
        let mut wire = match op {
            Op::ReduceMean => self.mean(&name, x, &axes)?,
            _ => self.wire(format!("{name}.sum"), Reduce::new(axes.iter().copied().collect(), Reducer::Sum), &[x])?,
        };
        if node.int("keepdims", 1) == 0 {
            for a in axes.iter().rev() {
                wire = self.wire(format!("{name}.rm{a}"), AxisOp::Rm(*a), &[wire])?;
            }
        }
        Ok(wire)
    }

    /// The mean of `x` over `axes` (kept, of length 1): their sum divided by their count, as
    /// tract's ONNX loader expands `ReduceMean`.
    fn mean(&mut self, name: &str, x: OutletId, axes: &[usize]) -> TractResult<OutletId> {
        let shape = self.shape(x)?;
        let count = tensor0(axes.iter().map(|a| shape[*a]).product::<usize>() as f32).broadcast_into_rank(shape.len())?;
        let count = self.model.add_const(format!("{name}.count"), count)?;
        let sum = self.wire(format!("{name}.sum"), Reduce::new(axes.iter().copied().collect(), Reducer::Sum), &[x])?;
        self.wire(name.to_string(), math::div(), &[sum, count])
    }

    /// `(x − mean) / √(var + ε) · scale (+ bias)` over the axes from `axis` on, as tract's ONNX
    /// loader expands it.
    fn layer_norm(&mut self, node: &Node, inputs: &[OutletId], rank: usize) -> TractResult<OutletId> {
        let name = &node.name;
        let x = inputs[0];
        let axes: Vec<usize> = (Self::axis(node.int("axis", -1), rank)?..rank).collect();
        let mean = self.mean(&format!("{name}.mean"), x, &axes)?;
        let d = self.wire(format!("{name}.d"), math::sub(), &[x, mean])?;
        let dd = self.wire(format!("{name}.dd"), math::square(), &[d])?;
        let var = self.mean(&format!("{name}.var"), dd, &axes)?;
        let eps = self.model.add_const(format!("{name}.epsilon"), tensor0(node.float("epsilon", 1e-5)).broadcast_into_rank(rank)?)?;
        let var_eps = self.wire(format!("{name}.var_eps"), math::add(), &[var, eps])?;
        let inv = self.wire(format!("{name}.inv_std_dev"), math::rsqrt(), &[var_eps])?;
        let normalized = self.wire(format!("{name}.normalized"), math::mul(), &[d, inv])?;
        let scaled = wire_with_rank_broadcast(format!("{name}.scaled"), &mut self.model, math::mul(), &[normalized, inputs[1]])?[0];
        match inputs.get(2) {
            Some(bias) => Ok(wire_with_rank_broadcast(format!("{name}.biased"), &mut self.model, math::add(), &[scaled, *bias])?[0]),
            None => Ok(scaled),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pvt3_format::onnx::{int, ints, AttributeProto, DataType, TensorProto};

    fn node(op: &str, inputs: &[&str], output: &str, attribute: Vec<AttributeProto>) -> Node {
        let input = inputs.iter().map(|s| s.to_string()).collect();
        Node { input, output: vec![output.into()], name: format!("{op}_{output}"), op_type: op.into(), attribute, domain: String::new() }
    }

    fn i64s(name: &str, v: &[i64]) -> TensorProto {
        TensorProto {
            dims: vec![v.len() as i64],
            data_type: DataType::Int64 as i32,
            name: name.into(),
            raw_data: v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            ..Default::default()
        }
    }

    fn run(graph: &Graph, shape: &[usize], x: &[f32], output: &str) -> (Vec<usize>, Vec<f32>) {
        let model = typed_model(graph, &[("x", f32::fact(shape))], &[output], Budget::of_file(0), 1).unwrap();
        let out =
            model.into_optimized().unwrap().into_runnable().unwrap().run(tvec!(Tensor::from_shape(shape, x).unwrap().into())).unwrap();
        (out[0].shape().to_vec(), out[0].to_plain_array_view::<f32>().unwrap().iter().copied().collect())
    }

    /// Shape arithmetic becomes constants: the batch read by `Shape` and `Slice`, joined by
    /// `Concat`, broadcasts a row with `Expand`; `Reshape` reads `-1` and `0` as ONNX says.
    #[test]
    fn shape_arithmetic_is_fixed_when_the_plan_is_built() {
        let graph = Graph {
            node: vec![
                node("Shape", &["x"], "shape", vec![]),
                node("Slice", &["shape", "zero", "one"], "batch", vec![]),
                node("Concat", &["batch", "three"], "target", vec![int("axis", 0)]),
                node("Expand", &["row", "target"], "rows", vec![]),
                node("Reshape", &["x", "keep_first"], "flat", vec![]),
                node("Add", &["rows", "flat"], "y", vec![]),
            ],
            initializer: vec![
                i64s("zero", &[0]),
                i64s("one", &[1]),
                i64s("three", &[3]),
                i64s("keep_first", &[0, -1]),
                TensorProto {
                    dims: vec![1, 3],
                    data_type: 1,
                    name: "row".into(),
                    float_data: vec![10.0, 20.0, 30.0],
                    ..Default::default()
                },
            ],
            ..Default::default()
        };
        let (shape, y) = run(&graph, &[2, 3, 1], &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0], "y");
        assert_eq!(shape, vec![2, 3]);
        assert_eq!(y, vec![11.0, 22.0, 33.0, 14.0, 25.0, 36.0]);
    }

    /// Reductions keep or drop their axes, a mean divides by the count, `Transpose` permutes,
    /// `Gather` picks, and `Softmax` normalises along its axis.
    #[test]
    fn reductions_permutations_and_gathers_follow_onnx() {
        let graph = Graph {
            node: vec![
                node("Transpose", &["x"], "t", vec![ints("perm", &[1, 0])]),
                node("ReduceMean", &["t"], "mean", vec![ints("axes", &[-1]), int("keepdims", 0)]),
                node("ReduceSum", &["t", "last"], "sum", vec![int("keepdims", 1)]),
                node("Gather", &["sum", "pick"], "picked", vec![int("axis", 0)]),
                node("Softmax", &["t"], "soft", vec![int("axis", -1)]),
            ],
            initializer: vec![i64s("last", &[1]), i64s("pick", &[2, 0])],
            ..Default::default()
        };
        let x = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        assert_eq!(run(&graph, &[2, 3], &x, "mean"), (vec![3], vec![2.5, 3.5, 4.5]));
        assert_eq!(run(&graph, &[2, 3], &x, "picked"), (vec![2, 1], vec![9.0, 5.0]));
        let (shape, soft) = run(&graph, &[2, 3], &x, "soft");
        assert_eq!(shape, vec![3, 2]);
        let low = 1.0 / (1.0 + 3f32.exp());
        for (got, want) in soft.iter().zip([low, 1.0 - low, low, 1.0 - low, low, 1.0 - low]) {
            assert!((got - want).abs() < 1e-6, "{got} {want}");
        }
    }

    /// What the runtime does not read is refused by name, never guessed at.
    #[test]
    fn unknown_operators_and_tensors_are_named() {
        let graph = Graph { node: vec![node("Conv", &["x", "w"], "y", vec![])], initializer: vec![i64s("w", &[1])], ..Default::default() };
        let err = typed_model(&graph, &[("x", f32::fact([1]))], &["y"], Budget::of_file(0), 1).unwrap_err();
        assert!(err.contains("operator Conv, which pvt3 does not export"), "{err}");
        let err = typed_model(&graph, &[("x", f32::fact([1]))], &["z"], Budget::of_file(0), 1).unwrap_err();
        assert!(err.contains("no tensor named `z`"), "{err}");
        let err = typed_model(&graph, &[("seam", f32::fact([1]))], &["y"], Budget::of_file(0), 1).unwrap_err();
        assert!(err.contains("no tensor named `seam`"), "{err}");
    }
}
