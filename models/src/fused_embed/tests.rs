//! The fused embedding against the same embedding composed of candle ops (forward ≤ 1e-6, every
//! gradient ≤ 1e-5 relative) and against finite differences, on both sensor presets and with a
//! patch mask that drops a patch.

use candle_core::{Tensor, Var};

use crate::gradcheck::{directional, max_abs, random, randomise, relative, smooth_loss};
use crate::{Config, Pvt3, Pvt3Config};

#[test]
fn fused_embedding_matches_composed_and_finite_differences() {
    let patch_selection = Config { network: Pvt3Config { patch_selection: true, ..Default::default() }.into(), ..Config::icub20() };
    // With a patch dropped, the mask's value there is zero and the loss jumps if it moves: no
    // finite difference for the mask there.
    let cases = [(Config::icub20(), false), (Config::biotac20(), false), (patch_selection.clone(), false), (patch_selection, true)];
    for (cfg, drop) in cases {
        let (model, varmap) = Pvt3::init(&cfg, 0).unwrap();
        let vars = randomise(&varmap, 1);
        let mut dropped = None;
        if let Some((_, mask)) = vars.iter().find(|(name, _)| name == "patch_mask" && drop) {
            let mut values = mask.to_vec1::<f32>().unwrap();
            values[1] = 0.0;
            mask.set(&Tensor::new(values, mask.device()).unwrap()).unwrap();
            dropped = Some(1);
        }
        let (t, n, p) = (cfg.time_tokens(), cfg.num_patches(), cfg.patch_dim());
        let patches = Var::from_tensor(&random(&[3, t, n, p], 2)).unwrap();
        let weights = random(&[3, t, n + 1 - dropped.iter().count(), cfg.dim], 3);
        let fused = model.embed(&patches).unwrap();
        let composed = model.embed_composed(&patches).unwrap();
        let forward = max_abs(&(&fused - &composed).unwrap());
        assert!(forward <= 1e-6 * max_abs(&composed).max(1.0), "{}: forward differs by {forward:e}", cfg.height);
        let backward = |y: &Tensor| (y * &weights).unwrap().tanh().unwrap().sum_all().unwrap().backward().unwrap();
        let (gf, gc) = (backward(&fused), backward(&composed));
        let embedding = ["patch_embed.weight", "patch_embed.bias", "frame_mask", "space_cls", "pos_embed", "patch_mask"];
        let named = vars.iter().filter(|(name, _)| embedding.contains(&name.as_str())).map(|(n, v)| (n.as_str(), v));
        let named: Vec<(&str, &Var)> = named.chain([("patches", &patches)]).collect();
        assert_eq!(named.len(), 6 + usize::from(cfg.patch_selection()));
        let loss = || smooth_loss(&model.embed(&patches).unwrap(), &weights);
        for (i, (name, var)) in named.into_iter().enumerate() {
            let (f, c) = (gf.get(var.as_tensor()).unwrap(), gc.get(var.as_tensor()).unwrap());
            let err = relative(f, c);
            assert!(err <= 1e-5 && max_abs(c) > 0.0, "{}: gradient of {name} differs by {err:e} (relative)", cfg.height);
            if drop && name == "patch_mask" {
                continue;
            }
            let (numeric, analytic) = directional(var, f, 10 + i as u64, loss);
            let err = (numeric - analytic).abs() / analytic.abs().max(1e-2);
            assert!(err < 1e-2, "{}: {name}: finite difference {numeric} against the backward's {analytic}", cfg.height);
        }
    }
}
