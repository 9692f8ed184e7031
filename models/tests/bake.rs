//! Baked models against their masked parents and against the golden logits.

use std::path::PathBuf;

use candle_core::{Device, Tensor};
use ndarray::{Array2, Array4};
use ndarray_npy::read_npy;

use pvt3_models::weights::varmap_tensors;
use pvt3_models::{Config, Pvt3, Pvt3Config, Rng};
use pvt3_spec::bake::bake;
use pvt3_spec::reference;
use pvt3_spec::weights::read_tensors;

fn golden(file: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/golden/icub20").join(file)
}

/// The six real iCub samples (and the zero and constant ones) of the golden input.
fn real_samples() -> (Vec<f32>, usize) {
    let x: Array4<f32> = read_npy(golden("input.npy")).unwrap();
    (x.iter().copied().collect(), x.shape()[0])
}

fn worst(a: &[Vec<f64>], b: impl IntoIterator<Item = f64>) -> f64 {
    a.iter().flatten().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

#[test]
fn golden_weights_baked_reproduce_the_golden_logits() {
    let baked = bake(&Config::icub20(), &read_tensors(&golden("weights.safetensors")).unwrap()).unwrap();
    let expected: Array2<f64> = read_npy(golden("logits.npy")).unwrap();
    let (x, b) = real_samples();
    let logits = reference::forward(&baked, &x, b).unwrap();
    let err = worst(&logits, expected.iter().copied());
    assert!(err <= 1e-5, "worst absolute error {err:e}");
    // The golden masks hold zeros: the baked model really is smaller.
    assert!(baked.kept_tokens.len() < 75);
    assert!(baked.space.layers.iter().any(|l| l.attn.head_dim < 64 && l.ffn.fc1.rows < 40));
    assert!(baked.parameter_count() < Config::icub20().parameter_count());
    assert!(baked.mult_adds() < Config::icub20().mult_adds());
}

/// Mask values in [0.25, 1.75] with the entries `zero(i)` set to zero.
fn set_mask(varmap: &candle_nn::VarMap, name: &str, rng: &mut Rng, zero: impl Fn(usize) -> bool) {
    let vars = varmap.data().lock().unwrap();
    let var = &vars[name];
    let n = var.elem_count();
    let values: Vec<f32> = (0..n).map(|i| if zero(i) { 0.0 } else { 0.25 + 1.5 * rng.uniform() }).collect();
    var.set(&Tensor::from_vec(values, n, &Device::Cpu).unwrap()).unwrap();
}

/// Bakes a masked icub20-shaped model and compares it with its parent on real samples.
fn check_against_parent(cfg: Config, prune_channels: bool, prune_frames: bool) {
    let (parent, varmap) = Pvt3::init(&cfg, 9).unwrap();
    let mut rng = Rng::new(10);
    let inner = cfg.inner_dim();
    for (prefix, depth) in [("space", cfg.space_depth), ("temporal", cfg.time_depth)] {
        for i in 0..depth {
            let p = format!("{prefix}.layers.{i}");
            if !prune_channels {
                set_mask(&varmap, &format!("{p}.attn.channel_mask"), &mut rng, |_| false);
                set_mask(&varmap, &format!("{p}.ffn.channel_mask"), &mut rng, |_| false);
            } else if i == 0 {
                // Every channel but one gone (the survivor in the last head).
                set_mask(&varmap, &format!("{p}.attn.channel_mask"), &mut rng, |c| c != inner - 2);
                set_mask(&varmap, &format!("{p}.ffn.channel_mask"), &mut rng, |u| u != 3);
            } else {
                // About half gone, unevenly across heads.
                set_mask(&varmap, &format!("{p}.attn.channel_mask"), &mut rng, |c| (c * 7 + i) % 3 == 0 || c < 3);
                set_mask(&varmap, &format!("{p}.ffn.channel_mask"), &mut rng, |u| (u * 5 + i) % 2 == 0);
            }
        }
    }
    set_mask(&varmap, "frame_mask", &mut rng, |t| prune_frames && t % 4 != 0);
    if cfg.patch_selection() {
        // Two of the grid's four patches gone, the others scaled.
        set_mask(&varmap, "patch_mask", &mut rng, |p| p == 1 || p == 2);
    }
    if cfg.spectral_bands() > 0 {
        // A standardisation of the spectral features other than the identity.
        set_mask(&varmap, "spectral.scale", &mut rng, |_| false);
        set_mask(&varmap, "spectral.shift", &mut rng, |_| false);
    }
    let baked = bake(&cfg, &varmap_tensors(&varmap).unwrap()).unwrap();
    if prune_channels {
        assert_eq!(baked.space.layers[0].ffn.fc1.rows, 1);
        assert_eq!(baked.space.layers[0].attn.head_dim, 1, "one channel in one head, a zero one in the others");
    }
    if prune_frames {
        assert_eq!(baked.kept_tokens.len(), cfg.time_tokens().div_ceil(4));
    }
    if cfg.patch_selection() {
        assert_eq!(baked.kept_patches, [0, 3]);
    }
    let (x, b) = real_samples();
    let input = Tensor::from_vec(x.clone(), (b, 6, 10, 75), &Device::Cpu).unwrap();
    let expected = parent.forward(&input, None).unwrap().flatten_all().unwrap().to_vec1::<f32>().unwrap();
    let got = reference::forward(&baked, &x, b).unwrap();
    let err = worst(&got, expected.iter().map(|v| *v as f64));
    assert!(err <= 1e-5, "{cfg:?} channels {prune_channels} frames {prune_frames}: worst {err:e}");
    let t = cfg.time_tokens();
    assert_eq!(baked.spectrum.is_some(), cfg.spectral_bands() > 0);
    // The touch so far (pruned tokens as their constants, a spectral head over its kept frames)
    // agrees too.
    for tokens in [1, 2, t / 3, t - 1] {
        let expected = parent.forward_prefix(&input, tokens, None).unwrap().flatten_all().unwrap().to_vec1::<f32>().unwrap();
        let got = reference::forward_prefix(&baked, &x, b, tokens).unwrap();
        let err = worst(&got, expected.iter().map(|v| *v as f64));
        assert!(err <= 1e-5, "{tokens} of {t} tokens, channels {prune_channels} frames {prune_frames}: worst {err:e}");
    }
    assert!(parent.forward_prefix(&input, 0, None).is_err() && reference::forward_prefix(&baked, &x, b, t + 1).is_err());
}

#[test]
fn baked_equals_masked_parent_with_one_head() {
    for (c, f) in [(true, false), (false, true), (true, true)] {
        check_against_parent(Config::icub20(), c, f);
    }
}

#[test]
fn baked_equals_masked_parent_with_several_heads_and_tubelets() {
    let cfg = Config { heads: 4, dim_head: 16, tubelet: 3, ..Config::icub20() };
    for (c, f) in [(true, false), (false, true), (true, true)] {
        check_against_parent(cfg.clone(), c, f);
    }
}

#[test]
fn baked_equals_masked_parent_with_a_spectral_head() {
    let cfg = Config { network: Pvt3Config { spectral_bands: 8, ..Default::default() }.into(), ..Config::icub20() };
    check_against_parent(cfg.clone(), true, true);
    let no_levels =
        Config { network: Pvt3Config { spectral_bands: 8, spectral_levels: false, ..Default::default() }.into(), ..cfg.clone() };
    check_against_parent(no_levels, true, true);
    let (parent, varmap) = Pvt3::init(&cfg, 9).unwrap();
    let baked = bake(&cfg, &varmap_tensors(&varmap).unwrap()).unwrap();
    // The head is counted: 2 · 60 · 9 standardisation values, a 20 × 540 map and its bias.
    let plain = bake(&Config::icub20(), &varmap_tensors(&Pvt3::init(&Config::icub20(), 9).unwrap().1).unwrap()).unwrap();
    assert_eq!(baked.parameter_count() - plain.parameter_count(), 2 * 540 + 20 * 540 + 20);
    assert_eq!(cfg.parameter_count() - Config::icub20().parameter_count(), 2 * 540 + 20 * 540 + 20);
    assert_eq!(baked.mult_adds() - plain.mult_adds(), cfg.mult_adds() - Config::icub20().mult_adds());
    assert!(cfg.spectral_mult_adds() > 20 * 540);
    assert!(parent.spectrum().is_some());
}

#[test]
fn baked_equals_masked_parent_with_pruned_patches() {
    let cfg = Config { network: Pvt3Config { patch_selection: true, ..Default::default() }.into(), ..Config::icub20() };
    for (c, f) in [(false, false), (true, true)] {
        check_against_parent(cfg.clone(), c, f);
    }
    // The pruned patches' tokens are gone: fewer multiply-adds than the unpruned model's.
    let (_, varmap) = Pvt3::init(&cfg, 9).unwrap();
    let whole = bake(&cfg, &varmap_tensors(&varmap).unwrap()).unwrap();
    assert_eq!(whole.kept_patches, [0, 1, 2, 3]);
    assert_eq!(whole.mult_adds(), Config::icub20().mult_adds());
    let plain = bake(&Config::icub20(), &varmap_tensors(&Pvt3::init(&Config::icub20(), 9).unwrap().1).unwrap()).unwrap();
    assert_eq!(whole.parameter_count(), plain.parameter_count() + 4, "the patch scale");
    let mut tensors = varmap_tensors(&varmap).unwrap();
    tensors.get_mut("patch_mask").unwrap().1[1] = 0.0;
    let pruned = bake(&cfg, &tensors).unwrap();
    assert_eq!(pruned.kept_patches, [0, 2, 3]);
    assert!(pruned.mult_adds() < whole.mult_adds() * 9 / 10, "{} of {}", pruned.mult_adds(), whole.mult_adds());
}

#[test]
fn missing_or_misshapen_tensors_cannot_be_baked() {
    let mut tensors = read_tensors(&golden("weights.safetensors")).unwrap();
    let msg = bake(&Config { dim_head: 32, ..Config::icub20() }, &tensors).unwrap_err().to_string();
    assert!(msg.contains("has shape [64], expected [32]"), "{msg}");
    tensors.remove("head.bias");
    let msg = bake(&Config::icub20(), &tensors).unwrap_err().to_string();
    assert!(msg.contains("`head.bias` is missing"), "{msg}");
}
