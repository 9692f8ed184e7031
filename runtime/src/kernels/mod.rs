//! Kernel choice for the plan's matrix products. tract picks a product's kernel (its tile of
//! mr × nr outputs) from a cost model fitted on large products. On this model's small ones
//! (k = 20, a few hundred rows) that model prefers a 40 × 2 tile, which ran 20–30 % slower here
//! than the best tile, and every tract kernel call has a fixed cost that dominates short sums
//! (docs/benchmarks.md, steps 15 and 17). [`Kernels`] says how a plan chooses instead: by a fixed
//! rule (the default, deterministic), tract's own way, or by timing every candidate on the
//! product's own shape. The arithmetic is the same: only the tile, the packing of the operands
//! and the order of the sums change.

use std::collections::HashMap;
use std::time::{Duration, Instant};

use tract_core::internal::*;
use tract_core::ops::matmul::optimized::{MatMulOperand, OptMatMul, ProtoFusedSpec};
use tract_core::ops::matmul::pack::{DynPackedExoticFact, OptMatMulPack};
use tract_core::ops::matmul::ModePicker;
use tract_core::tract_linalg::mmm::{
    retain_best, AsInputValue, EagerPackedInput, FusedSpec, MMMInputFormat, MMMInputValue, MatMatMul, MmmDispatch, OutputStoreSpec,
    PackedMatrixStorage, Query,
};
use tract_core::tract_linalg::pack::PackedFormat;

#[cfg(target_arch = "x86_64")]
use x86_64::small_products::{self, Combine, Epilogue, Isa, SmallProduct, Source};

#[cfg(target_arch = "x86_64")]
mod x86_64;

/// How a plan chooses the kernel of each matrix product.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Kernels {
    /// By a fixed rule (the default): on one thread, on x86-64 with AVX-512 or with AVX2 and FMA,
    /// the runtime's own product for short sums wherever it applies, in the widest instruction
    /// set (both sum in the same order, so they give the same bits), except, with AVX2, on large
    /// products with long sums (`short_enough`); tract's own choice for every other product.
    /// With AVX-512, timing kept the runtime's product on every shape tried, k from 20 to 4800
    /// (docs/benchmarks.md, step 18). Nothing is timed: the same file on the same machine gets
    /// the same plan, hence bit-identical outputs, and a plan costs only tract's optimisation.
    #[default]
    Fixed,
    /// tract's own choice for every product.
    Tract,
    /// Timed at each plan's first call (50–100 ms per plan of the iCub model): every kernel tract
    /// could run on the product's own shape, and the runtime's product in each instruction set
    /// the machine has; the fastest stays. Two loads can choose differently, so outputs can
    /// differ in the last bits. Worth it where the fixed rule keeps tract's kernels: other CPUs
    /// (ARM), multi-threaded plans.
    Measured,
}

impl std::str::FromStr for Kernels {
    type Err = String;

    /// `fixed`, `tract` or `measured`.
    fn from_str(name: &str) -> Result<Self, String> {
        match name {
            "fixed" => Ok(Kernels::Fixed),
            "tract" => Ok(Kernels::Tract),
            "measured" => Ok(Kernels::Measured),
            other => Err(format!("kernel choice `{other}` is none of fixed, tract, measured")),
        }
    }
}

/// Time spent measuring one kernel on one product, at most (and at least `MIN_RUNS` runs).
const BUDGET: Duration = Duration::from_millis(1);
const MIN_RUNS: usize = 3;
const MAX_RUNS: usize = 30;
/// A kernel replaces tract's pick only when it is faster by more than this fraction, so that
/// noise alone does not move a product.
const MARGIN: f64 = 0.05;

/// What a product runs with.
#[derive(Clone)]
enum Choice {
    /// One of tract's kernels, with the index of its packing.
    Tract(Box<dyn MatMatMul>, usize),
    /// The runtime's [`SmallProduct`] with these instructions.
    #[cfg(target_arch = "x86_64")]
    Small(Isa),
}

/// One operand of a product as the tuner sees it.
enum Operand {
    /// A constant, by its plain `[k, mn]` values.
    Const(Tensor),
    /// An input of the product, packed by node `pack` (for this product alone); `zeros` has its
    /// unpacked shape.
    Packed { pack: usize, zeros: Tensor, k_axis: usize, mn_axis: usize },
}

impl Operand {
    /// What the time of a product depends on: the operand's kind, shape and axes.
    fn key(&self) -> String {
        match self {
            Operand::Const(_) => "const".into(),
            Operand::Packed { zeros, k_axis, mn_axis, .. } => format!("{:?} k{k_axis} mn{mn_axis}", zeros.shape()),
        }
    }

    /// This operand packed in `format`.
    fn prepare(&self, format: &dyn MMMInputFormat) -> TractResult<Box<dyn MMMInputValue>> {
        match self {
            Operand::Const(w) => format.prepare_one(w, 0, 1),
            Operand::Packed { zeros, k_axis, mn_axis, .. } => format.prepare_one(zeros, *k_axis, *mn_axis),
        }
    }
}

/// A product the tuner can rewire: `a` (m rows) times `b` (n columns) over k.
struct Product {
    node: usize,
    a: Operand,
    b: Operand,
    m: usize,
    k: usize,
    n: usize,
}

/// A product as the runtime's own [`SmallProduct`], with the node inputs it reads.
#[cfg(target_arch = "x86_64")]
type Small = (SmallProduct, TVec<OutletId>);
/// Off x86-64 the runtime has no product of its own: a type without values.
#[cfg(not(target_arch = "x86_64"))]
enum Small {}

/// Chooses the kernel of every product of `model`, optimised by tract, as `kernels` says, and
/// returns how many products changed kernel. [`Classifier`](crate::Classifier) does this to
/// every plan it builds; it is public for callers who build their own tract plans. `threads`:
/// the threads the plan will run on. With more than one, products keep tract's kernels, which
/// split their tiles across threads, and the runtime's product (one thread) is not used.
pub fn tune(model: &mut TypedModel, threads: usize, kernels: Kernels) -> TractResult<usize> {
    if kernels == Kernels::Tract {
        return Ok(0);
    }
    let mut changed = 0;
    // Products of one shape (the same layer in every block) are measured once.
    let mut measured: HashMap<String, Option<Choice>> = HashMap::new();
    for node in model.eval_order()? {
        let Some(product) = product(model, node)? else { continue };
        let small = if threads == 1 { small(model, &product)? } else { None };
        let choice = match kernels {
            Kernels::Fixed => fixed(small.as_ref()),
            _ => {
                let op = model.node(node).op_as::<OptMatMul>().unwrap();
                let current = (op.mmm[0].name().to_string(), packing(op));
                let c = (&op.c_fact.shape, op.c_m_axis, op.c_n_axis, op.micro_ops.len());
                let key =
                    format!("{}x{}x{} {} | {} | {current:?} {c:?}", product.m, product.k, product.n, product.a.key(), product.b.key());
                match measured.get(&key) {
                    Some(choice) => choice.clone(),
                    None => {
                        let choice = fastest(model, &product, &current, small.as_ref())?;
                        measured.insert(key, choice.clone());
                        choice
                    }
                }
            }
        };
        match choice {
            Some(Choice::Tract(mmm, ix)) => replace(model, &product, mmm, ix)?,
            #[cfg(target_arch = "x86_64")]
            Some(Choice::Small(isa)) => {
                let (op, inputs) = small.expect("chosen only where it applies");
                rewire(model, &product, SmallProduct { isa, ..op }, &inputs)?
            }
            None => continue,
        }
        changed += 1;
    }
    Ok(changed)
}

/// The fixed rule's choice: the runtime's product where it applies (`small`, built by [`small`]
/// with the widest instruction set) and [`short_enough`] says so; otherwise tract's own pick
/// (`None`).
fn fixed(small: Option<&Small>) -> Option<Choice> {
    #[cfg(target_arch = "x86_64")]
    return small.filter(|(op, _)| short_enough(op)).map(|(op, _)| Choice::Small(op.isa));
    #[cfg(not(target_arch = "x86_64"))]
    small.map(|s| match *s {})
}

/// With AVX2 (8 lanes, register blocks of 4 rows by 3 vectors), the runtime's product loses to
/// tract's packed 16 × 6 kernel on large products with long sums, as the camera model's
/// `325 × 64 × 128`, `300 × 300 × 64` and a matrix times a vector of 1,200 (their times:
/// docs/benchmarks.md, "The kernel rule on AVX2"). It keeps
/// every product with sums of at most [`AVX2_SHORT_SUM`], and longer ones with fewer outputs than
/// [`AVX2_MANY_OUTPUTS`] and sums shorter than [`AVX2_LONG_SUM`]: every product of the iCub and
/// BioTac files. With AVX-512 it keeps every product (step 18 of the same page).
#[cfg(target_arch = "x86_64")]
fn short_enough(op: &SmallProduct) -> bool {
    match op.isa {
        Isa::Avx512 => true,
        Isa::Avx2 => op.k <= AVX2_SHORT_SUM || (op.m * op.n < AVX2_MANY_OUTPUTS && op.k < AVX2_LONG_SUM),
    }
}

#[cfg(target_arch = "x86_64")]
const AVX2_SHORT_SUM: usize = 32;
#[cfg(target_arch = "x86_64")]
const AVX2_MANY_OUTPUTS: usize = 16_384;
#[cfg(target_arch = "x86_64")]
const AVX2_LONG_SUM: usize = 1_024;

/// What beats `current` on `p` by more than the margin, if anything: one of tract's kernels
/// (and packing), or `small`, the product as the runtime's own.
fn fastest(model: &TypedModel, p: &Product, current: &(String, usize), small: Option<&Small>) -> TractResult<Option<Choice>> {
    let mut best: Option<(f64, Choice)> = None;
    let mut current_time = f64::MAX;
    for (mmm, ix) in candidates(p) {
        let t = time(&*mmm, ix, p)?;
        if mmm.name() == current.0 && ix == current.1 {
            current_time = t;
        } else if best.as_ref().is_none_or(|b| t < b.0) {
            best = Some((t, Choice::Tract(mmm, ix)));
        }
    }
    #[cfg(target_arch = "x86_64")]
    if let Some((op, inputs)) = small {
        let values = inputs
            .iter()
            .map(|o| {
                let fact = model.outlet_fact(*o)?;
                match &fact.konst {
                    Some(k) => Ok(k.clone().into_tvalue()),
                    None => Ok(Tensor::zero::<f32>(fact.shape.as_concrete().context("a symbolic input")?)?.into_tvalue()),
                }
            })
            .collect::<TractResult<Vec<_>>>()?;
        for isa in small_products::instruction_sets() {
            let op = SmallProduct { isa, ..op.clone() };
            let t = best_of(|| op.run(&values).map(drop))?;
            if best.as_ref().is_none_or(|b| t < b.0) {
                best = Some((t, Choice::Small(isa)));
            }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (model, small.map(|s| match *s {}));
    Ok(best.filter(|b| b.0 < current_time * (1.0 - MARGIN)).map(|b| b.1))
}

/// Off x86-64 no product runs as the runtime's own.
#[cfg(not(target_arch = "x86_64"))]
fn small(_: &TypedModel, _: &Product) -> TractResult<Option<Small>> {
    Ok(None)
}

/// `p` as a [`SmallProduct`] (with the first instruction set this machine has), with the inputs
/// it reads (each packed operand's unpacked input), if the machine can run one and everything
/// tract fused into the product is an operation the small product runs.
#[cfg(target_arch = "x86_64")]
fn small(model: &TypedModel, p: &Product) -> TractResult<Option<Small>> {
    let Some(&isa) = small_products::instruction_sets().first() else { return Ok(None) };
    let node = model.node(p.node);
    let op = node.op_as::<OptMatMul>().unwrap();
    let (Some(c_m_axis), Some(c_shape)) = (op.c_m_axis, op.c_fact.shape.as_concrete()) else {
        return Ok(None);
    };
    let mut inputs = node.inputs.clone();
    let mut source = |o: &Operand| match o {
        Operand::Const(t) => Source::Const(Arc::new(t.clone())),
        Operand::Packed { pack, k_axis, mn_axis, .. } => {
            // The input the pack feeds (`operand` found the product's operand there).
            let input = node.inputs.iter().position(|o| o.node == *pack).expect("a packed operand reads its pack");
            inputs[input] = model.node(*pack).inputs[0];
            Source::Input { input, k_axis: *k_axis, mn_axis: *mn_axis }
        }
    };
    let (a, b) = (source(&p.a), source(&p.b));
    let (mut epilogues, mut scalar) = (vec![], None);
    for u in &op.micro_ops {
        let (input, op, len) = match u {
            ProtoFusedSpec::AddMatMul { .. } | ProtoFusedSpec::Store(_) => continue,
            ProtoFusedSpec::BinPerRow(v, op, _) => (*v, *op, p.m),
            ProtoFusedSpec::BinPerCol(v, op, _) => (*v, *op, p.n),
            ProtoFusedSpec::BinScalar(v, op) => (*v, *op, 1),
            _ => return Ok(None),
        };
        let fact = model.outlet_fact(node.inputs[input])?;
        let (Some(op), true, None) =
            (Combine::from_tract(op), fact.datum_type == f32::datum_type() && fact.shape.volume() == len.to_dim(), scalar)
        else {
            // Not an operation the small product runs, or one after the scalar (which it applies last).
            return Ok(None);
        };
        match u {
            ProtoFusedSpec::BinScalar(..) => scalar = Some((input, op)),
            _ => epilogues.push(Epilogue { input, op, per_row: matches!(u, ProtoFusedSpec::BinPerRow(..)) }),
        }
    }
    let (c_shape, c_n_axis) = (c_shape.into(), op.c_n_axis);
    let op = SmallProduct { m: p.m, k: p.k, n: p.n, a, b, epilogues, scalar, c_shape, c_m_axis, c_n_axis, isa };
    Ok(op.supported().then_some((op, inputs.into())))
}

/// Puts `op` in place of product `p`, reading `inputs`; the packing nodes it no longer reads
/// drop out of the plan.
#[cfg(target_arch = "x86_64")]
fn rewire(model: &mut TypedModel, p: &Product, op: SmallProduct, inputs: &[OutletId]) -> TractResult<()> {
    for (slot, outlet) in inputs.iter().enumerate() {
        if model.node(p.node).inputs[slot] != *outlet {
            model.add_edge(*outlet, InletId::new(p.node, slot))?;
        }
    }
    model.node_mut(p.node).op = Box::new(op);
    Ok(())
}

/// The packing a single-kernel product runs with.
fn packing(op: &OptMatMul) -> usize {
    op.micro_ops
        .iter()
        .find_map(|u| match u {
            ProtoFusedSpec::AddMatMul { packings, .. } => Some(packings[0].0),
            _ => None,
        })
        .unwrap_or(0)
}

/// `node` as a tunable product: one f32 kernel, one product, no batch axes, each operand a
/// constant or an input packed for this product alone. `None` for anything else, which keeps
/// tract's pick.
fn product(model: &TypedModel, node: usize) -> TractResult<Option<Product>> {
    let n = model.node(node);
    let Some(op) = n.op_as::<OptMatMul>() else { return Ok(None) };
    if op.mmm.len() != 1 || op.mode_picker != ModePicker::Single || !op.trivial_path || op.c_fact.datum_type != f32::datum_type() {
        return Ok(None);
    }
    let products: Vec<_> = op
        .micro_ops
        .iter()
        .filter_map(|u| match u {
            ProtoFusedSpec::AddMatMul { a, b, packings, geo } => Some((a, b, packings, geo)),
            _ => None,
        })
        .collect();
    let [(a, b, packings, geo)] = products[..] else { return Ok(None) };
    if packings.len() != 1 || packings[0].1.is_some() {
        return Ok(None);
    }
    let (Some(a), Some(b)) = (operand(model, n, a)?, operand(model, n, b)?) else { return Ok(None) };
    let dim = |axis: Option<usize>| axis.map_or(Ok(1), |ax| op.c_fact.shape[ax].to_usize());
    Ok(Some(Product { node, a, b, m: dim(op.c_m_axis)?, k: geo.k.to_usize()?, n: dim(op.c_n_axis)? }))
}

fn operand(model: &TypedModel, node: &TypedNode, operand: &MatMulOperand) -> TractResult<Option<Operand>> {
    let input = match operand {
        MatMulOperand::Const(v) => return Ok(unpack(&**v)?.map(Operand::Const)),
        MatMulOperand::Input(i) => node.inputs[*i],
    };
    let pack = model.node(input.node);
    if pack.op_as::<OptMatMulPack>().is_none() || model.outlet_successors(input).len() != 1 {
        return Ok(None);
    }
    let in_fact = model.outlet_fact(pack.inputs[0])?;
    let Some(shape) = in_fact.shape.as_concrete() else { return Ok(None) };
    let mapping = pack.op.as_typed().unwrap().axes_mapping(&[in_fact], &[model.outlet_fact(input)?])?;
    let (k_axis, mn_axis) = (mapping.axis('K')?.inputs[0][0], mapping.axis('M')?.inputs[0][0]);
    // One matrix: every other axis is a unit axis (what `Pack` packs).
    let one_matrix = shape.iter().enumerate().all(|(ax, d)| ax == k_axis || ax == mn_axis || *d == 1);
    if in_fact.datum_type != f32::datum_type() || !one_matrix {
        return Ok(None);
    }
    Ok(Some(Operand::Packed { pack: pack.id, zeros: Tensor::zero::<f32>(shape)?, k_axis, mn_axis }))
}

/// The plain `[k, mn]` values of a constant operand packed in a plain f32 format.
fn unpack(value: &dyn MMMInputValue) -> TractResult<Option<Tensor>> {
    let Some(eager) = value.downcast_ref::<EagerPackedInput>() else { return Ok(None) };
    let Some(format) = eager.fact.format.downcast_ref::<PackedFormat>() else { return Ok(None) };
    if format.dt != f32::datum_type() {
        return Ok(None);
    }
    let (k, mn) = (eager.k(), eager.mn());
    let mut weights = Tensor::zero::<f32>(&[k, mn])?;
    let mut column = vec![0f32; k];
    {
        let mut w = weights.to_plain_array_view_mut::<f32>()?;
        for j in 0..mn {
            format.extract_at_mn_f32(eager, j, &mut column)?;
            for (i, v) in column.iter().enumerate() {
                w[[i, j]] = *v;
            }
        }
    }
    Ok(Some(weights))
}

/// The kernels tract could run for this product: compiled for this CPU's best instruction sets,
/// packing plain f32 on both sides, with a tile of more than one column unless n is 1.
fn candidates(p: &Product) -> Vec<(Box<dyn MatMatMul>, usize)> {
    let mut suitable = MmmDispatch::native().suitable(&Query::plain(f32::datum_type(), Some(p.m), Some(p.k), Some(p.n)));
    suitable.retain(|(mmm, _, pe)| pe.is_none() && mmm.arch().is_some());
    retain_best(&mut suitable);
    suitable
        .into_iter()
        .filter(|(mmm, ix, _)| {
            let (a, b) = &mmm.packings()[*ix];
            let plain = |f: &dyn MMMInputFormat| f.downcast_ref::<PackedFormat>().is_some_and(|f| f.dt == f32::datum_type());
            plain(&**a) && plain(&**b) && (mmm.nr() > 1 || p.n == 1)
        })
        .map(|(mmm, ix, _)| (mmm.clone(), ix))
        .collect()
}

/// The fastest of a few runs of packing the inputs and multiplying, in seconds.
fn time(mmm: &dyn MatMatMul, packing: usize, p: &Product) -> TractResult<f64> {
    let (fa, fb) = &mmm.packings()[packing];
    let konst = |o: &Operand, f: &dyn MMMInputFormat| match o {
        Operand::Const(_) => o.prepare(f).map(Some),
        Operand::Packed { .. } => Ok(None),
    };
    let (ka, kb) = (konst(&p.a, &**fa)?, konst(&p.b, &**fb)?);
    let mut c = Tensor::zero::<f32>(&[p.m, p.n])?;
    // SAFETY: the store describes `c`, a contiguous `[m, n]` f32 tensor: items of f32's size,
    // rows n items apart, columns adjacent.
    let store = unsafe { mmm.c_from_data_and_strides(size_of::<f32>(), p.n as isize, 1) };
    best_of(|| {
        let a = match &ka {
            Some(k) => AsInputValue::Borrowed(&**k),
            None => AsInputValue::Owned(p.a.prepare(&**fa)?),
        };
        let b = match &kb {
            Some(k) => AsInputValue::Borrowed(&**k),
            None => AsInputValue::Owned(p.b.prepare(&**fb)?),
        };
        // SAFETY: `a` and `b` were packed for this kernel's `packing`, with k and the m and n
        // the run is given; the store wraps a view of `c`, which holds m × n values.
        unsafe {
            let view = c.view_mut();
            mmm.run(p.m, p.n, &[FusedSpec::AddMatMul { a, b, packing }, FusedSpec::Store(store.wrap(&view))])
        }
    })
}

/// The fastest of a few runs of `f` (within the budget), in seconds.
fn best_of(mut f: impl FnMut() -> TractResult<()>) -> TractResult<f64> {
    let started = Instant::now();
    let mut best = f64::MAX;
    for run in 0..MAX_RUNS {
        let t = Instant::now();
        f()?;
        best = best.min(t.elapsed().as_secs_f64());
        if run + 1 >= MIN_RUNS && started.elapsed() > BUDGET {
            break;
        }
    }
    Ok(best)
}

/// Rewires `p` to `mmm`: its inputs packed for that kernel, its constants repacked, its stores
/// tiled by the kernel's mr × nr.
fn replace(model: &mut TypedModel, p: &Product, mmm: Box<dyn MatMatMul>, packing: usize) -> TractResult<()> {
    let (fa, fb) = mmm.packings()[packing].clone();
    let mut constants = [None, None];
    for (i, (operand, format)) in [(&p.a, fa), (&p.b, fb)].into_iter().enumerate() {
        match operand {
            Operand::Const(_) => constants[i] = Some(operand.prepare(&*format)?),
            Operand::Packed { pack, k_axis, mn_axis, .. } => {
                let op = Pack { format, k_axis: *k_axis, mn_axis: *mn_axis };
                let in_fact = model.outlet_fact(model.node(*pack).inputs[0])?.clone();
                let fact = op.output_facts(&[&in_fact])?.remove(0);
                let node = model.node_mut(*pack);
                node.op = Box::new(op);
                node.outputs[0].fact = fact;
            }
        }
    }
    let (mr, nr) = (mmm.mr(), mmm.nr());
    let mut op = model.node(p.node).op_as::<OptMatMul>().unwrap().clone();
    for uop in &mut op.micro_ops {
        match uop {
            ProtoFusedSpec::AddMatMul { a, b, packings, .. } => {
                *packings = vec![(packing, None)];
                for (operand, konst) in [a, b].into_iter().zip(&constants) {
                    if let Some(k) = konst {
                        *operand = MatMulOperand::Const(k.clone());
                    }
                }
            }
            ProtoFusedSpec::Store(specs) => specs.iter_mut().for_each(|s| retile(s, mr, nr)),
            ProtoFusedSpec::AddUnicast(spec, _, _) => retile(spec, mr, nr),
            _ => (),
        }
    }
    op.mmm = vec![mmm];
    model.node_mut(p.node).op = Box::new(op);
    Ok(())
}

fn retile(spec: &mut OutputStoreSpec, tile_m: usize, tile_n: usize) {
    match spec {
        OutputStoreSpec::View { mr, nr, .. } | OutputStoreSpec::Strides { mr, nr, .. } => {
            *mr = tile_m;
            *nr = tile_n;
        }
    }
}

/// Packs a product's input for the kernel [`tune`] chose, as tract's `OptMatMulPack` does, in a
/// format tract's own selection would not have given it (whose fields tract keeps private).
#[derive(Debug, Clone, Hash, PartialEq, Eq)]
struct Pack {
    format: Box<dyn MMMInputFormat>,
    k_axis: usize,
    mn_axis: usize,
}

impl Pack {
    /// The input's shape without its k and mn axes (all ones: [`operand`] checks it).
    fn rest<D: Clone>(&self, shape: &[D]) -> TVec<D> {
        shape.iter().enumerate().filter(|(ax, _)| *ax != self.k_axis && *ax != self.mn_axis).map(|(_, d)| d.clone()).collect()
    }
}

impl Op for Pack {
    fn name(&self) -> StaticName {
        "TunedPack".into()
    }

    fn info(&self) -> TractResult<Vec<String>> {
        Ok(vec![format!("{:?}, k axis {}, mn axis {}", self.format, self.k_axis, self.mn_axis)])
    }

    op_as_typed_op!();
}

impl EvalOp for Pack {
    op_out_of_plan!();

    fn eval(&self, _ctx: &EvalContext, inputs: TVec<TValue>) -> TractResult<TVec<TValue>> {
        let input = &inputs[0];
        let packed = self.format.prepare_one_view(&input.view(), self.k_axis, self.mn_axis)?;
        let shape: TVec<usize> = self.rest(input.shape());
        Ok(tvec!(PackedMatrixStorage::new_batched(&shape, tvec!(packed)).into_tensor(input.datum_type()).into_tvalue()))
    }
}

impl TypedOp for Pack {
    fn output_facts(&self, inputs: &[&TypedFact]) -> TractResult<TVec<TypedFact>> {
        let shape = &inputs[0].shape;
        let exotic =
            DynPackedExoticFact { k: shape[self.k_axis].clone(), mn: shape[self.mn_axis].clone(), packers: vec![self.format.clone()] };
        Ok(tvec!(inputs[0].datum_type.fact(&*self.rest(shape)).with_exotic_fact(exotic)))
    }

    as_op!();
}

#[cfg(test)]
mod tests {
    use super::*;
    use tract_core::ops::einsum::EinSum;
    use tract_core::ops::math::add;

    /// `h = x W + b` (a constant operand) and `h yᵀ` (two packed inputs), optimised by tract.
    fn two_products() -> TypedModel {
        let mut model = TypedModel::default();
        let x = model.add_source("x", f32::fact([37, 20])).unwrap();
        let y = model.add_source("y", f32::fact([29, 40])).unwrap();
        let w: Vec<f32> = (0..20 * 40).map(|i| ((i * 7 % 23) as f32 - 11.0) / 17.0).collect();
        let w = model.add_const("w", Tensor::from_shape(&[20, 40], &w).unwrap()).unwrap();
        let b = model.add_const("b", Tensor::from_shape(&[1, 40], &(0..40).map(|i| i as f32 / 10.0).collect::<Vec<_>>()).unwrap()).unwrap();
        let einsum = |expr: &str| EinSum::new(expr.parse().unwrap(), f32::datum_type());
        let xw = model.wire_node("xw", einsum("mk,kn->mn"), &[x, w]).unwrap()[0];
        let h = model.wire_node("h", add(), &[xw, b]).unwrap()[0];
        let s = model.wire_node("s", einsum("mk,nk->mn"), &[h, y]).unwrap()[0];
        model.select_output_outlets(&[h, s]).unwrap();
        model.into_optimized().unwrap()
    }

    fn run(model: &TypedModel, x: &Tensor) -> Vec<Vec<f32>> {
        let y = Tensor::from_shape(&[29, 40], &(0..29 * 40).map(|i| ((i * 11 % 31) as f32 - 15.0) / 8.0).collect::<Vec<_>>()).unwrap();
        let outputs = model.clone().into_runnable().unwrap().run(tvec!(x.clone().into(), y.into())).unwrap();
        outputs.iter().map(|o| o.to_plain_array_view::<f32>().unwrap().iter().copied().collect()).collect()
    }

    fn worst(a: &[Vec<f32>], b: &[Vec<f32>]) -> f32 {
        a.iter().flatten().zip(b.iter().flatten()).map(|(p, q)| (p - q).abs() / q.abs().max(1.0)).fold(0.0, f32::max)
    }

    /// Every kernel the tuner may pick, put in by `replace` (or [`SmallProduct`] by `rewire`, in
    /// every instruction set the tests cover), computes what tract's pick computes.
    #[test]
    fn every_candidate_kernel_computes_the_same_products() {
        let model = two_products();
        let x = Tensor::from_shape(&[37, 20], &(0..37 * 20).map(|i| ((i * 13 % 29) as f32 - 14.0) / 9.0).collect::<Vec<_>>()).unwrap();
        let expected = run(&model, &x);
        let products: Vec<Product> = model.eval_order().unwrap().into_iter().filter_map(|n| product(&model, n).unwrap()).collect();
        assert!(products.iter().any(|p| matches!(p.b, Operand::Const(_)) || matches!(p.a, Operand::Const(_))), "a product by a constant");
        assert!(
            products.iter().any(|p| matches!((&p.a, &p.b), (Operand::Packed { .. }, Operand::Packed { .. }))),
            "a product of two inputs"
        );
        let mut tried = 0;
        for p in &products {
            let candidates = candidates(p);
            assert!(!candidates.is_empty(), "{}x{}x{}: no candidate kernel", p.m, p.k, p.n);
            for (mmm, ix) in candidates {
                let name = mmm.name().to_string();
                let mut rewired = model.clone();
                replace(&mut rewired, p, mmm, ix).unwrap();
                let err = worst(&run(&rewired, &x), &expected);
                assert!(err < 1e-5, "{name} on {}x{}x{}: {err:e}", p.m, p.k, p.n);
                tried += 1;
            }
            #[cfg(target_arch = "x86_64")]
            for isa in small_products::covered() {
                let (op, inputs) = small(&model, p).unwrap().expect("a product the small kernel runs");
                let mut rewired = model.clone();
                rewire(&mut rewired, p, SmallProduct { isa, ..op }, &inputs).unwrap();
                let err = worst(&run(&rewired, &x), &expected);
                assert!(err < 1e-5, "SmallProduct ({isa:?}) on {}x{}x{}: {err:e}", p.m, p.k, p.n);
                tried += 1;
            }
        }
        for kernels in [Kernels::Fixed, Kernels::Measured] {
            let mut tuned = model.clone();
            tune(&mut tuned, 1, kernels).unwrap();
            assert!(worst(&run(&tuned, &x), &expected) < 1e-5, "{kernels:?}");
        }
        // On x86-64 tract offers several kernels per shape; on ARM (here, qemu's CPU) it offers
        // one, which `replace` must still repack and retile correctly.
        #[cfg(target_arch = "x86_64")]
        assert!(tried > 2 * products.len(), "{tried} kernels tried on {} products: too few alternatives", products.len());
        assert!(tried >= products.len());
    }

    /// Whether product `node` reads an input packed once for two uses (tract does so for `q kᵀ`
    /// where both sides pack alike, as on ARM): the tuner leaves such a product to tract, since
    /// repacking the shared node would change what its other reader gets.
    fn shares_a_pack(model: &TypedModel, node: usize) -> bool {
        model.node(node).inputs.iter().any(|i| model.node(i.node).op_is::<OptMatMulPack>() && model.outlet_successors(*i).len() > 1)
    }

    /// The plan tract makes of the committed golden model has the structure the kernel choice
    /// relies on: every matrix product is one the tuner recognises (one kernel, one product, a
    /// constant or singly packed operand each), except, where tract packs one input for both
    /// operands, products that read it (on ARM; none on x86-64); and on x86-64 the fixed rule
    /// gives every product to the runtime's own. A tract whose plans look otherwise fails here,
    /// loudly, rather than leaving products silently untuned.
    #[test]
    fn the_golden_plan_has_the_structure_the_kernel_choice_expects() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/golden/icub20/model.onnx");
        let model = crate::plan::optimised(crate::Classifier::load(path).unwrap().tract_model(1).unwrap(), &[]).unwrap();
        let products: Vec<usize> = model.nodes().iter().filter(|n| n.op_is::<OptMatMul>()).map(|n| n.id).collect();
        assert!(products.len() >= 40, "{} matrix products in the golden plan", products.len());
        let declined: Vec<usize> = products.iter().copied().filter(|n| product(&model, *n).unwrap().is_none()).collect();
        for n in &declined {
            assert!(shares_a_pack(&model, *n), "{}: a product the tuner does not recognise", model.node(*n).name);
        }
        assert!(declined.len() <= products.len() / 4, "{} of {} products declined", declined.len(), products.len());
        #[cfg(target_arch = "x86_64")]
        assert!(declined.is_empty(), "x86-64 packs each operand apart");
        let mut fixed = model.clone();
        let changed = tune(&mut fixed, 1, Kernels::Fixed).unwrap();
        #[cfg(target_arch = "x86_64")]
        {
            assert_eq!(changed, products.len(), "the fixed rule gives every product to the runtime's own");
            let small: Vec<&SmallProduct> = fixed.nodes().iter().filter_map(|n| n.op_as::<SmallProduct>()).collect();
            assert_eq!(small.len(), products.len());
            // The head's two products, as the runtime's one-round decluttering leaves them: a
            // vector without an n axis, and one scaled by a value of the plan (golden.rs checks
            // their logits).
            assert!(small.iter().any(|p| p.c_n_axis.is_none()), "a product into a vector");
            assert!(small.iter().any(|p| p.scalar.is_some()), "a product with a scalar epilogue");
        }
        #[cfg(not(target_arch = "x86_64"))]
        assert_eq!(changed, 0, "off x86-64 the fixed rule keeps tract's choice");
        let mut off = model.clone();
        assert_eq!(tune(&mut off, 1, Kernels::Tract).unwrap(), 0);
        assert_eq!(tune(&mut off, 2, Kernels::Fixed).unwrap(), 0, "multi-threaded plans keep tract's kernels");
    }
}
