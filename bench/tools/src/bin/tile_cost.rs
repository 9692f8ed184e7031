//! What one of tract's kernel calls costs: `cargo run --release -p pvt3-bench-tools --bin
//! tile_cost` times tract's f32 kernels on `384 × k × 48` products with packed operands, for k
//! from 1 to 160, and prints the time per tile of outputs (docs/benchmarks.md, step 17). A
//! straight line through these gives the fixed cost of a tile and the cost of one step of k.

use std::time::Instant;

use tract_onnx::prelude::*;
use tract_onnx::tract_core::tract_linalg::mmm::{retain_best, AsInputValue, FusedSpec, MmmDispatch, Query};
use tract_onnx::tract_core::tract_linalg::pack::PackedFormat;

const M: usize = 384;
const N: usize = 48;

fn main() -> TractResult<()> {
    let ks = [1, 4, 20, 40, 80, 160];
    println!("| kernel | tiles | {} |", ks.map(|k| format!("k = {k} (ns per tile)")).join(" | "));
    println!("|---|---:|{}", "---:|".repeat(ks.len()));
    let mut kernels = MmmDispatch::native().suitable(&Query::plain(f32::datum_type(), Some(M), Some(20), Some(N)));
    kernels.retain(|(mmm, _, pe)| pe.is_none() && mmm.arch().is_some() && mmm.nr() > 1);
    retain_best(&mut kernels);
    for (mmm, ix, _) in kernels {
        let (fa, fb) = &mmm.packings()[ix];
        if fa.downcast_ref::<PackedFormat>().is_none() || fb.downcast_ref::<PackedFormat>().is_none() {
            continue;
        }
        let tiles = M.div_ceil(mmm.mr()) * N.div_ceil(mmm.nr());
        let mut row = vec![];
        for k in ks {
            let (a, b) = (fa.prepare_one(&Tensor::zero::<f32>(&[k, M])?, 0, 1)?, fb.prepare_one(&Tensor::zero::<f32>(&[k, N])?, 0, 1)?);
            let mut c = Tensor::zero::<f32>(&[M, N])?;
            // SAFETY: the store describes `c`, a contiguous `[M, N]` f32 tensor.
            let store = unsafe { mmm.c_from_data_and_strides(4, N as isize, 1) };
            let mut best = f64::MAX;
            for _ in 0..2000 {
                let t = Instant::now();
                // SAFETY: `a` and `b` were packed for this kernel's packing `ix` with k, M and N;
                // the store wraps a view of `c`, which holds M × N values.
                unsafe {
                    let view = c.view_mut();
                    let specs = [
                        FusedSpec::AddMatMul { a: AsInputValue::Borrowed(&*a), b: AsInputValue::Borrowed(&*b), packing: ix },
                        FusedSpec::Store(store.wrap(&view)),
                    ];
                    mmm.run(M, N, &specs)?;
                }
                best = best.min(t.elapsed().as_secs_f64());
            }
            row.push(format!("{:.0}", best * 1e9 / tiles as f64));
        }
        println!("| {} | {tiles} | {} |", mmm.name(), row.join(" | "));
    }
    Ok(())
}
