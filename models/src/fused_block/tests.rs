//! The fused block against the same block composed of candle ops (forward ≤ 1e-6, every gradient
//! ≤ 1e-5 relative), against finite differences, and for the same bits on any thread count.

use candle_core::{DType, Device, Var};
use candle_nn::{VarBuilder, VarMap};

use super::{pack, BlockDims, BlockOp};
use crate::gradcheck::{directional, max_abs, random, randomise, relative, smooth_loss};
use crate::transformer::Block;
use crate::{Config, Rng};

/// A block with every parameter random, and its variables by name.
fn block(cfg: &Config, seed: u64) -> (Block, Vec<(String, Var)>) {
    let varmap = VarMap::new();
    let block = Block::new(cfg, VarBuilder::from_varmap(&varmap, DType::F32, &Device::Cpu)).unwrap();
    (block, randomise(&varmap, seed))
}

/// The configurations tested: the iCub block (one head; 5 and 76 tokens, the short loops and the
/// gemm path of attention) and a two-head one on both paths.
fn configs() -> Vec<(Config, usize)> {
    let icub = Config { dropout: 0.1, ..Config::icub20() };
    let two_heads = Config { heads: 2, dim_head: 8, dim: 12, mlp_dim: 24, ..icub.clone() };
    vec![(icub.clone(), 5), (icub, 76), (two_heads.clone(), 9), (two_heads, 20)]
}

#[test]
fn fused_matches_composed_in_value_and_every_gradient() {
    for (cfg, tokens) in configs() {
        let (block, vars) = block(&cfg, 1);
        let x = Var::from_tensor(&random(&[3, tokens, cfg.dim], 2)).unwrap();
        let weights = random(&[3, tokens, cfg.dim], 3);
        for (train, first) in [(false, false), (true, false), (false, true), (true, true)] {
            // `first`: the CLS token's output alone, against the composed block's first token.
            let weights = if first { weights.narrow(1, 0, 1).unwrap() } else { weights.clone() };
            let run = |fused: bool| {
                let mut rng = Rng::new(4);
                let rng = train.then_some(&mut rng);
                let y = match (fused, first) {
                    (true, false) => block.forward(&x, rng),
                    (true, true) => block.forward_first(&x, rng),
                    (false, _) => {
                        block
                            .forward_composed(&x, block.draw_dropout(rng).as_ref())
                            .map(|y| if first { y.narrow(1, 0, 1).unwrap() } else { y })
                    }
                }
                .unwrap();
                let grads = (&y * &weights).unwrap().sum_all().unwrap().backward().unwrap();
                (y, grads)
            };
            let ((yf, gf), (yc, gc)) = (run(true), run(false));
            assert_eq!(yf.dims(), yc.dims());
            let forward = max_abs(&(&yf - &yc).unwrap());
            assert!(
                forward <= 1e-6 * max_abs(&yc).max(1.0),
                "{tokens} tokens, train {train}, first {first}: forward differs by {forward:e}"
            );
            let named = vars.iter().map(|(n, v)| (n.as_str(), v.as_tensor())).chain([("input", x.as_tensor())]);
            for (name, var) in named {
                let (f, c) = (gf.get(var).unwrap(), gc.get(var).unwrap());
                let err = relative(f, c);
                assert!(err <= 1e-5, "{tokens} tokens, train {train}, first {first}: gradient of {name} differs by {err:e} (relative)");
                assert!(max_abs(c) > 0.0, "{name} has a zero gradient: the test would prove nothing");
            }
        }
    }
}

#[test]
fn gradients_match_finite_differences() {
    // For each parameter and the input: the directional derivative along a random direction, by
    // central differences of a smooth scalar in f32, against the backward's gradient.
    for (cfg, tokens) in configs() {
        let cfg = Config { dropout: 0.0, ..cfg };
        let (block, vars) = block(&cfg, 5);
        let x = Var::from_tensor(&random(&[2, tokens, cfg.dim], 6)).unwrap();
        let weights = random(&[2, tokens, cfg.dim], 7);
        for first in [false, true] {
            let forward = |x: &Var| if first { block.forward_first(x, None) } else { block.forward(x, None) }.unwrap();
            let weights = if first { weights.narrow(1, 0, 1).unwrap() } else { weights.clone() };
            let loss = || smooth_loss(&forward(&x), &weights);
            // Evaluation mode: the backward recomputes the activations instead of reading kept ones.
            let y = forward(&x);
            let grads = (&y * &weights).unwrap().tanh().unwrap().sum_all().unwrap().backward().unwrap();
            let named = vars.iter().map(|(n, v)| (n.as_str(), v)).chain([("input", &x)]);
            for (i, (name, var)) in named.enumerate() {
                let (numeric, analytic) = directional(var, grads.get(var.as_tensor()).unwrap(), 100 + i as u64, loss);
                // f32 rounding leaves ~1e-3 (measured: at most 6e-3 here); a wrong formula is off by O(1).
                let err = (numeric - analytic).abs() / analytic.abs().max(1e-2);
                assert!(err < 1e-2, "{tokens} tokens, first {first}, {name}: finite difference {numeric} against the backward's {analytic} ({err:e} relative)");
            }
        }
    }
}

#[test]
fn threads_change_no_bit() {
    let (cfg, tokens) = (Config { dropout: 0.1, ..Config::icub20() }, 5);
    let (block, vars) = block(&cfg, 8);
    // 300 sequences of 5 tokens: eight chunks of work.
    let x = Var::from_tensor(&random(&[300, tokens, cfg.dim], 9)).unwrap();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            let y = block.forward(&x, Some(&mut Rng::new(10))).unwrap();
            let grads = y.sqr().unwrap().sum_all().unwrap().backward().unwrap();
            let mut bits: Vec<u32> = y.flatten_all().unwrap().to_vec1::<f32>().unwrap().iter().map(|v| v.to_bits()).collect();
            for (_, v) in &vars {
                bits.extend(grads.get(v.as_tensor()).unwrap().flatten_all().unwrap().to_vec1::<f32>().unwrap().iter().map(|v| v.to_bits()));
            }
            bits
        })
    };
    assert_eq!(run(1), run(3));
}

/// A block too large to keep its activations recomputes them in its backward: the same bits as
/// when kept, and `BlockDims::activations` counts exactly what a kept forward holds.
#[test]
fn recomputed_activations_give_the_same_bits_and_are_counted_exactly() {
    let (cfg, tokens) = (Config { dropout: 0.1, ..Config::icub20() }, 20);
    let (block, vars) = block(&cfg, 11);
    let dims = BlockDims::new(&cfg);
    let by_name: std::collections::HashMap<_, _> = vars.iter().map(|(n, v)| (n.clone(), v.as_tensor().clone())).collect();
    let packed = pack(dims.parameters().iter().map(|(name, _)| &by_name[name])).unwrap();
    let x = Var::from_tensor(&random(&[30, tokens, cfg.dim], 12)).unwrap();
    for first in [false, true] {
        let run = |keep: bool| {
            let dropout = block.draw_dropout(Some(&mut Rng::new(13)));
            let y = BlockOp::new(dims, dropout, keep, first).apply(&x, &packed).unwrap();
            let grads = y.sqr().unwrap().sum_all().unwrap().backward().unwrap();
            let mut bits: Vec<u32> = y.flatten_all().unwrap().to_vec1::<f32>().unwrap().iter().map(|v| v.to_bits()).collect();
            for t in std::iter::once(&x).chain(vars.iter().map(|(_, v)| v)) {
                bits.extend(grads.get(t.as_tensor()).unwrap().flatten_all().unwrap().to_vec1::<f32>().unwrap().iter().map(|v| v.to_bits()));
            }
            bits
        };
        assert_eq!(run(true), run(false), "first only: {first}");
        let op = BlockOp::new(dims, block.draw_dropout(Some(&mut Rng::new(13))), true, first);
        let (xs, p) = (x.flatten_all().unwrap().to_vec1::<f32>().unwrap(), packed.to_vec1::<f32>().unwrap());
        let kept: usize = op
            .run_forward(&xs, &p, &op.effective(&p), 30, tokens, true)
            .iter()
            .map(|(_, a)| {
                [&a.xhat1, &a.rstd1, &a.a, &a.qkv, &a.probs, &a.heads, &a.xhat2, &a.rstd2, &a.c, &a.h, &a.cdf, &a.gd]
                    .iter()
                    .map(|v| v.len())
                    .sum::<usize>()
            })
            .sum();
        assert_eq!(dims.activations(30, tokens, op.queries(tokens)), kept, "first only: {first}");
    }
}
