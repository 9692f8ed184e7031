//! The model against the independent golden implementation, its size, and its gradients.

use std::path::PathBuf;

use candle_core::{Device, Tensor};
use ndarray::{Array2, Array4};
use ndarray_npy::read_npy;

use super::Pvt3;
use crate::weights::{load_weights, save_weights};
use crate::{Config, Error, Pvt3Config};

fn golden(file: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/golden/icub20").join(file)
}

#[test]
fn golden_icub20_logits_reproduced_in_f32() {
    let (model, varmap) = Pvt3::init(&Config::icub20(), 0).unwrap();
    load_weights(&varmap, &golden("weights.safetensors")).unwrap();
    let input: Array4<f32> = read_npy(golden("input.npy")).unwrap();
    let expected: Array2<f64> = read_npy(golden("logits.npy")).unwrap();
    let x = Tensor::from_vec(input.iter().copied().collect(), input.shape(), &Device::Cpu).unwrap();
    let logits = model.forward(&x, None).unwrap().to_vec2::<f32>().unwrap();
    let worst = logits.iter().flatten().zip(expected.iter()).map(|(a, b)| (*a as f64 - b).abs()).fold(0.0, f64::max);
    assert!(worst <= 1e-5, "worst absolute error {worst:e}");
}

#[test]
fn icub20_has_64272_trainable_parameters_besides_the_frame_mask() {
    let (_, varmap) = Pvt3::init(&Config::icub20(), 0).unwrap();
    let vars = varmap.data().lock().unwrap();
    let count: usize = vars.iter().filter(|(n, _)| *n != "frame_mask").map(|(_, v)| v.elem_count()).sum();
    assert_eq!(count, 64_272);
    assert_eq!(vars["frame_mask"].elem_count(), 75);
    assert_eq!(count, Config::icub20().parameter_count());
}

#[test]
fn weights_round_trip_and_foreign_checkpoints_are_named() {
    let dir = std::env::temp_dir().join(format!("pvt3-weights-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("w.safetensors");
    let (model, varmap) = Pvt3::init(&Config::icub20(), 3).unwrap();
    save_weights(&varmap, &path).unwrap();
    let (copy, copy_vars) = Pvt3::init(&Config::icub20(), 4).unwrap();
    load_weights(&copy_vars, &path).unwrap();
    let x = Tensor::ones((1, 6, 10, 75), candle_core::DType::F32, &Device::Cpu).unwrap();
    let diff = (model.forward(&x, None).unwrap() - copy.forward(&x, None).unwrap()).unwrap();
    assert_eq!(diff.abs().unwrap().max_all().unwrap().to_scalar::<f32>().unwrap(), 0.0);

    let (_, other) = Pvt3::init(&Config { dim_head: 32, ..Config::icub20() }, 0).unwrap();
    let msg = load_weights(&other, &path).unwrap_err().to_string();
    assert!(msg.contains("`space.layers.0.attn.channel_mask` has shape [64], the configuration expects [32]"), "{msg}");

    std::fs::write(&path, b"not safetensors").unwrap();
    let msg = load_weights(&varmap, &path).unwrap_err().to_string();
    assert!(msg.contains("not a valid safetensors file"), "{msg}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn wrong_input_shape_is_a_clear_error() {
    let (model, _) = Pvt3::init(&Config::icub20(), 0).unwrap();
    let x = Tensor::zeros((2, 19, 1, 400), candle_core::DType::F32, &Device::Cpu).unwrap();
    match model.forward(&x, None) {
        Err(Error::Spec(pvt3_spec::Error::InputShape { got, expected })) => {
            assert_eq!(got, vec![2, 19, 1, 400]);
            assert_eq!(expected, "6, 10, 75");
        }
        other => panic!("expected an input-shape error, got {other:?}"),
    }
}

#[test]
fn gelsight_preset_runs_on_rgb_video() {
    let cfg = Config { classes: 5, ..Config::gelsight() };
    let (model, _) = Pvt3::init(&cfg, 0).unwrap();
    let x = Tensor::zeros((1, 240, 320, 3, 25), candle_core::DType::F32, &Device::Cpu).unwrap();
    assert_eq!(model.forward(&x, None).unwrap().dims(), &[1, 5]);
    assert_eq!(model.patchify(&x).unwrap().dims(), &[1, 25, 48, 4800]);
}

/// A fresh PVT³ (several heads and tubelets, a spectral head) has exactly the variables of the
/// table of names (`pvt3_spec::names::pvt3_variables`), with its shapes: the modules, baking,
/// pruning and the fused pack all name them from there.
#[test]
fn a_fresh_model_has_exactly_the_variables_of_the_table() {
    let configs = [
        Config::icub20(),
        Config { heads: 2, dim_head: 8, tubelet: 3, ..Config::icub20() },
        Config { network: Pvt3Config { spectral_bands: 16, ..Default::default() }.into(), ..Config::biotac20() },
    ];
    for cfg in configs {
        let (_, varmap) = Pvt3::init(&cfg, 1).unwrap();
        let mut got: Vec<(String, Vec<usize>)> =
            varmap.data().lock().unwrap().iter().map(|(n, v)| (n.clone(), v.dims().to_vec())).collect();
        let mut table: Vec<(String, Vec<usize>)> = pvt3_spec::names::pvt3_variables(&cfg).into_iter().map(|v| (v.name, v.shape)).collect();
        got.sort();
        table.sort();
        assert!(!table.is_empty());
        assert_eq!(got, table, "{cfg:?}");
    }
}

/// Patch dropout: a training step reads the window as the model whose patch mask is zero on the
/// patches the step's draws drop (one uniform draw a patch, dropped below `patch_dropout`);
/// evaluation reads every patch.
#[test]
fn patch_dropout_trains_on_the_patches_its_draws_keep_and_evaluates_on_all() {
    let network = Pvt3Config { patch_selection: true, patch_dropout: 0.5, ..Default::default() }.into();
    let cfg = Config { network, dropout: 0.0, ..Config::icub20() };
    let (model, varmap) = Pvt3::init(&cfg, 0).unwrap();
    crate::gradcheck::randomise(&varmap, 1);
    let x = crate::gradcheck::random(&[2, 6, 10, 75], 2);
    let seed = 3;
    let mut replay = crate::Rng::new(seed);
    let dropped: Vec<usize> = (0..cfg.num_patches()).filter(|_| (replay.uniform() as f64) < 0.5).collect();
    assert!(!dropped.is_empty() && dropped.len() < cfg.num_patches(), "seed {seed} drops {dropped:?}: choose one that drops some");
    let evaluated = model.forward(&x, None).unwrap();
    let trained = model.forward(&x, Some(&mut crate::Rng::new(seed))).unwrap();

    let mask = varmap.data().lock().unwrap()["patch_mask"].clone();
    let mut values = mask.to_vec1::<f32>().unwrap();
    dropped.iter().for_each(|&p| values[p] = 0.0);
    mask.set(&Tensor::new(values, &Device::Cpu).unwrap()).unwrap();
    let masked = model.forward(&x, None).unwrap();
    let differ = |a: &Tensor, b: &Tensor| (a - b).unwrap().abs().unwrap().max_all().unwrap().to_scalar::<f32>().unwrap();
    assert!(differ(&trained, &masked) <= 1e-6, "{}", differ(&trained, &masked));
    assert!(differ(&evaluated, &masked) > 1e-3, "evaluation reads the dropped patches too");
}
