//! Where the runtime spends its time: `cargo run --release -p pvt3-bench-tools --bin profile --
//! MODEL.onnx [BATCH [RUNS]]` times every node of the optimised tract plan over RUNS runs on
//! synthetic input and prints the time per operator kind, largest first (docs/benchmarks.md),
//! then the plan's median time without the per-node timing. It first says what building the plan
//! cost (the runtime's first call does the same): the tract model, tract's decluttering and
//! optimisation, the kernel choice.
//! With `PVT3_PROFILE_NODES=N` it also lists the N slowest single nodes with their output shapes.
//! With `PVT3_PROFILE_SHAPE=D0,D1,…` it runs any one-input ONNX file at that input shape
//! (`bench/products.py` times single products this way). The plan's products get the kernels
//! the runtime would give them by default, or as `PVT3_PROFILE_KERNELS=fixed|tract|measured`
//! says (`pvt3_runtime::Kernels`); `PVT3_PROFILE_INFO` adds each node's details (for a product: its shape and kernel).

use std::collections::HashMap;
use std::time::{Duration, Instant};

use tract_onnx::prelude::*;
use tract_onnx::tract_core::plan::{eval, SimplePlan, SimpleState};

type Failure = Box<dyn std::error::Error>;

/// The model at `path` and its input shape: a pvt3 model as the runtime builds it, or with
/// `PVT3_PROFILE_SHAPE` any one-input file through tract's ONNX loader.
fn load(path: &str, batch: usize) -> Result<(Vec<usize>, TypedModel), Failure> {
    if let Ok(dims) = std::env::var("PVT3_PROFILE_SHAPE") {
        let shape = dims.split(',').map(str::parse).collect::<Result<Vec<usize>, _>>()?;
        let model = tract_onnx::onnx().model_for_path(path)?.with_input_fact(0, f32::fact(&shape).into())?.into_typed()?;
        return Ok((shape, model));
    }
    let c = pvt3_runtime::Classifier::load(path)?;
    let mut shape = vec![batch];
    shape.extend(c.sample_shape());
    Ok((shape, c.tract_model(batch)?))
}

/// What the runtime's plans do to `model` (its decluttering, tract's optimisation, the kernels'
/// choice), each step's cost printed beside what reading and wiring the file cost (`built`): the
/// first call's work (docs/deploy.md, start-up).
fn plan(mut model: TypedModel, built: Duration) -> Result<Arc<TypedSimplePlan>, Failure> {
    let nodes = model.nodes().len();
    let started = Instant::now();
    pvt3_runtime::declutter(&mut model)?;
    let decluttered = started.elapsed();
    let started = Instant::now();
    model.optimize()?;
    let optimised = started.elapsed();
    let started = Instant::now();
    let kernels = std::env::var("PVT3_PROFILE_KERNELS").map_or(Ok(pvt3_runtime::Kernels::default()), |k| k.parse())?;
    pvt3_runtime::tune_kernels(&mut model, 1, kernels)?;
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    println!(
        "plan: file read and wired {:.1} ms ({nodes} nodes), decluttered {:.1} ms, optimised {:.1} ms ({} nodes), kernels chosen {:.1} ms\n",
        ms(built),
        ms(decluttered),
        ms(optimised),
        model.nodes().len(),
        ms(started.elapsed())
    );
    Ok(SimplePlan::new(model)?)
}

/// Seconds in all over `runs` runs (after 5 to warm up): by operator kind (with its calls), by
/// node, and of the whole plan.
struct Timed {
    by_op: HashMap<String, (f64, usize)>,
    by_node: HashMap<usize, f64>,
    total: f64,
}

fn time_nodes(plan: &Arc<TypedSimplePlan>, input: &Tensor, runs: usize) -> TractResult<Timed> {
    let mut timed = Timed { by_op: HashMap::new(), by_node: HashMap::new(), total: 0.0 };
    for run in 0..runs + 5 {
        let mut state = SimpleState::new(plan)?;
        let started = Instant::now();
        state.run_plan_with_eval(tvec!(input.clone().into()), |session, op_state, node, inputs| {
            let t = Instant::now();
            let out = eval(session, op_state, node, inputs);
            if run >= 5 {
                let e = timed.by_op.entry(node.op().name().into_owned()).or_default();
                e.0 += t.elapsed().as_secs_f64();
                e.1 += 1;
                *timed.by_node.entry(node.id).or_default() += t.elapsed().as_secs_f64();
            }
            out
        })?;
        if run >= 5 {
            timed.total += started.elapsed().as_secs_f64();
        }
    }
    Ok(timed)
}

/// The plan's median time over `runs` runs (after 5), run plainly: one reused state, no timing
/// per node.
fn median_plain(plan: &Arc<TypedSimplePlan>, input: &Tensor, runs: usize) -> TractResult<f64> {
    let mut state = SimpleState::new(plan)?;
    let mut plain: Vec<f64> = (0..runs + 5)
        .map(|_| {
            let started = Instant::now();
            state.run(tvec!(input.clone().into())).map(|_| started.elapsed().as_secs_f64())
        })
        .collect::<TractResult<_>>()?;
    plain.sort_by(f64::total_cmp);
    Ok(plain[plain.len() / 2])
}

/// The `n` slowest nodes with their output shapes (and with `PVT3_PROFILE_INFO`, their details).
fn print_nodes(plan: &Arc<TypedSimplePlan>, by_node: HashMap<usize, f64>, runs: usize, n: usize) {
    let mut nodes: Vec<_> = by_node.into_iter().collect();
    nodes.sort_by(|a, b| b.1.total_cmp(&a.1));
    let info = std::env::var("PVT3_PROFILE_INFO").is_ok();
    println!(
        "\n| node | operator | output | µs per run |{}\n|---|---|---|---:|{}",
        if info { " details |" } else { "" },
        if info { "---|" } else { "" }
    );
    for (id, secs) in nodes.into_iter().take(n) {
        let node = plan.model().node(id);
        let details = if info { format!(" {} |", node.op().info().unwrap_or_default().join("; ")) } else { String::new() };
        println!("| {} | {} | {:?} | {:.1} |{details}", node.name, node.op().name(), node.outputs[0].fact.shape, secs / runs as f64 * 1e6);
    }
}

fn main() -> Result<(), Failure> {
    // SAFETY: first thing in main, before any other thread exists. As pvt3-run does, so that
    // products time as they run there (glibc otherwise page-faults large outputs in anew).
    unsafe { pvt3_runtime::keep_freed_memory() };
    let args: Vec<String> = std::env::args().skip(1).collect();
    let path = args.first().ok_or("usage: profile MODEL.onnx [BATCH [RUNS]]")?;
    let batch: usize = args.get(1).map_or(Ok(1), |v| v.parse())?;
    let runs: usize = args.get(2).map_or(Ok(200), |v| v.parse())?;
    let started = Instant::now();
    let (shape, model) = load(path, batch)?;
    let plan = plan(model, started.elapsed())?;
    let n: usize = shape.iter().product();
    let input = Tensor::from_shape(&shape, &(0..n).map(|i| (i % 7) as f32 - 3.0).collect::<Vec<_>>())?;
    let Timed { by_op, by_node, total } = time_nodes(&plan, &input, runs)?;
    let mut rows: Vec<_> = by_op.into_iter().collect();
    rows.sort_by(|a, b| b.1 .0.total_cmp(&a.1 .0));
    println!("| operator | nodes | µs per run | share |\n|---|---:|---:|---:|");
    for (op, (secs, calls)) in rows {
        println!("| {op} | {} | {:.1} | {:.1} % |", calls / runs, secs / runs as f64 * 1e6, 100.0 * secs / total);
    }
    println!("| **whole plan** | {} | {:.1} | |", plan.model().nodes().len(), total / runs as f64 * 1e6);
    println!("| whole plan, untimed nodes (median) | | {:.1} | |", median_plain(&plan, &input, runs)? * 1e6);
    if let Some(n) = std::env::var("PVT3_PROFILE_NODES").ok().and_then(|v| v.parse().ok()) {
        print_nodes(&plan, by_node, runs, n);
    }
    Ok(())
}
