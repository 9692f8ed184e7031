//! Pruning a trained tiny model (channels, frames and patches): the pruned entries stay zero through fine-tuning, and the baked
//! fine-tuned model equals its masked parent.

use indicatif::ProgressBar;
use pvt3_models::weights::varmap_tensors;
use pvt3_spec::bake::bake;
use pvt3_spec::prune::{PatchChoice, PruneSpec, Scope};
use pvt3_spec::reference;

use super::*;
use crate::data::windows::Samples;
use crate::train::tests::{out_dir, spec, tiny_data};

#[test]
fn pruned_entries_stay_zero_and_the_baked_model_matches() {
    let data = tiny_data();
    let (dense, pruned) = (out_dir("prune-dense"), out_dir("prune-ft"));
    let mut s = spec(&data, 8, None);
    s.options.pruning.l1 = 0.05;
    s.config.network = pvt3_models::Pvt3Config { patch_selection: true, ..Default::default() }.into();
    train(&s, &dense, false, &ProgressBar::hidden()).unwrap().unwrap();
    let stage = PruneStage {
        spec: PruneSpec {
            channels: 50.0,
            frames: 50.0,
            patches: 50.0,
            scope: Scope::Local,
            weights: 0.0,
            patch_choice: PatchChoice::Magnitude,
        },
        epochs: 4,
        lr: 1e-3,
        kept_patches: None,
    };
    let r = prune_and_fine_tune(&dense, &data, &stage, &pruned, false, &ProgressBar::hidden()).unwrap().unwrap();
    assert!(r.test_accuracy > 0.0);

    let (meta, model, varmap) = checkpoint::load(&pruned).unwrap();
    assert_eq!(meta.provenance.pruning, Some(stage.spec.clone()));
    let tensors = varmap_tensors(&varmap).unwrap();
    let zeros = |name: &str| tensors[name].1.iter().filter(|v| **v == 0.0).count();
    assert_eq!(zeros("frame_mask"), 2, "half of the 4 temporal tokens");
    assert_eq!(zeros("patch_mask"), 1, "one of the 2 patches");
    assert_eq!(zeros("space.layers.0.attn.channel_mask"), 4, "half of each head's 4 channels");
    assert_eq!(zeros("temporal.layers.0.ffn.channel_mask"), 4);

    let baked = bake(&meta.config, &tensors).unwrap();
    assert_eq!((baked.kept_tokens.len(), baked.kept_patches.len()), (2, 1));
    let split = data.split(0).unwrap();
    let normalised = Samples::new(&data, &split.test, &meta.normalization);
    let rows: Vec<usize> = (0..normalised.len()).collect();
    let (x, _) = normalised.batch(&rows, |_| {}).unwrap();
    let expected = model.forward(&x, None).unwrap().flatten_all().unwrap().to_vec1::<f32>().unwrap();
    let got = reference::forward(&baked, &x.flatten_all().unwrap().to_vec1::<f32>().unwrap(), rows.len()).unwrap();
    let worst = got.iter().flatten().zip(&expected).map(|(a, b)| (a - *b as f64).abs()).fold(0.0, f64::max);
    assert!(worst < 1e-5, "worst {worst:e}");
    std::fs::remove_dir_all(dense).unwrap();
    std::fs::remove_dir_all(pruned).unwrap();
}

/// Persistent random pruning: the share of every weight matrix drawn after training is zero in
/// the fine-tuned model and nowhere else zero, and the masks are untouched.
#[test]
fn randomly_pruned_weights_stay_zero_through_fine_tuning() {
    let data = tiny_data();
    let (dense, pruned) = (out_dir("rp-dense"), out_dir("rp-ft"));
    train(&spec(&data, 3, None), &dense, false, &ProgressBar::hidden()).unwrap().unwrap();
    let stage = PruneStage {
        spec: PruneSpec {
            channels: 0.0,
            frames: 0.0,
            patches: 0.0,
            scope: Scope::Local,
            weights: 25.0,
            patch_choice: PatchChoice::Magnitude,
        },
        epochs: 3,
        lr: 1e-3,
        kept_patches: None,
    };
    prune_and_fine_tune(&dense, &data, &stage, &pruned, false, &ProgressBar::hidden()).unwrap().unwrap();
    let (_, _, parent) = checkpoint::load(&dense).unwrap();
    let (meta, _, varmap) = checkpoint::load(&pruned).unwrap();
    assert_eq!(meta.provenance.pruning, Some(stage.spec.clone()));
    let (before, after) = (varmap_tensors(&parent).unwrap(), varmap_tensors(&varmap).unwrap());
    let mut matrices = 0;
    for (name, (shape, values)) in &after {
        let zeros = values.iter().filter(|v| **v == 0.0).count();
        if pvt3_spec::names::Role::of(name, shape.len()) == pvt3_spec::names::Role::Matrix {
            matrices += 1;
            assert_eq!(zeros, (values.len() as f64 * 0.25).round() as usize, "{name}");
            let moved = values.iter().zip(&before[name].1).filter(|(a, b)| **a != 0.0 && a != b).count();
            assert!(moved > 0, "{name}: the kept entries are fine-tuned");
        } else if name.ends_with("mask") {
            assert_eq!(zeros, 0, "{name}: masks untouched");
        }
    }
    assert!(matrices >= 10, "{matrices} weight matrices");
    std::fs::remove_dir_all(dense).unwrap();
    std::fs::remove_dir_all(pruned).unwrap();
}

/// Choosing by validation keeps the patch that tells the classes apart (the tiny data's ramps are
/// on taxel 0, in patch 0) and leaves the parent's mask as it was; the fine-tuned run holds the
/// other patch at zero, and a stage that names its patches (a final model's) keeps those.
#[test]
fn patches_chosen_by_validation_keep_the_one_that_tells_the_classes_apart() {
    let data = tiny_data();
    let (dense, pruned, named) = (out_dir("pv-dense"), out_dir("pv-ft"), out_dir("pv-named"));
    let mut s = spec(&data, 8, None);
    s.config.network = pvt3_models::Pvt3Config { patch_selection: true, ..Default::default() }.into();
    train(&s, &dense, false, &ProgressBar::hidden()).unwrap().unwrap();
    let (meta, model, varmap) = checkpoint::load(&dense).unwrap();
    let mask = |varmap: &candle_nn::VarMap| varmap_tensors(varmap).unwrap()["patch_mask"].1.clone();
    let trained = mask(&varmap);
    let validation = Samples::new(&data, &data.split(0).unwrap().val, &meta.normalization);
    let keep = patch_choice::by_validation(&model, &varmap, &validation, 1, &ProgressBar::hidden()).unwrap();
    assert_eq!(keep, vec![true, false]);
    assert_eq!(mask(&varmap), trained, "the parent's mask restored");

    let spec =
        PruneSpec { channels: 0.0, frames: 0.0, patches: 50.0, scope: Scope::Local, weights: 0.0, patch_choice: PatchChoice::Validation };
    let stage = PruneStage { spec, epochs: 2, lr: 1e-3, kept_patches: None };
    prune_and_fine_tune(&dense, &data, &stage, &pruned, false, &ProgressBar::hidden()).unwrap().unwrap();
    let fine_tuned = mask(&checkpoint::load(&pruned).unwrap().2);
    assert!(fine_tuned[0] != 0.0 && fine_tuned[1] == 0.0, "{fine_tuned:?}");

    let stage = PruneStage { kept_patches: Some(vec![false, true]), ..stage };
    prune_and_fine_tune(&dense, &data, &stage, &named, false, &ProgressBar::hidden()).unwrap().unwrap();
    let fine_tuned = mask(&checkpoint::load(&named).unwrap().2);
    assert!(fine_tuned[0] == 0.0 && fine_tuned[1] != 0.0, "{fine_tuned:?}");
    for dir in [dense, pruned, named] {
        std::fs::remove_dir_all(dir).unwrap();
    }
}

/// A head over the image's space reads a pruned patch's pixels as 0, so pruning patches fits it
/// again: the fine-tuned run's standardisation makes what the head now reads of each training
/// frame mean 0 and variance 1, feature by feature, as a fit does; the parent's does not.
#[test]
fn pruning_patches_fits_a_head_over_the_image_again() {
    let data = tiny_data();
    let (dense, pruned) = (out_dir("ph-dense"), out_dir("ph-ft"));
    let mut s = spec(&data, 2, None);
    let network = pvt3_models::Pvt3Config { patch_selection: true, spectral_bands: 1, spectral_space: true, ..Default::default() };
    s.config.network = network.into();
    train(&s, &dense, false, &ProgressBar::hidden()).unwrap().unwrap();
    let spec =
        PruneSpec { channels: 0.0, frames: 0.0, patches: 50.0, scope: Scope::Local, weights: 0.0, patch_choice: PatchChoice::Magnitude };
    prune_and_fine_tune(
        &dense,
        &data,
        &PruneStage { spec, epochs: 1, lr: 1e-3, kept_patches: None },
        &pruned,
        false,
        &ProgressBar::hidden(),
    )
    .unwrap()
    .unwrap();
    let (meta, model, varmap) = checkpoint::load(&pruned).unwrap();
    let pvt3 = model.pvt3("the test").unwrap();
    let train_set = Samples::new(&data, &data.split(0).unwrap().train, &meta.normalization);
    let (x, _) = train_set.batch(&(0..train_set.len()).collect::<Vec<_>>(), |_| {}).unwrap();
    let read = pvt3.spectrum().unwrap().frame_features(&pvt3.head_frames(&x).unwrap(), &[1.0; 8]).unwrap();
    let moments = |varmap: &candle_nn::VarMap| -> (Vec<f32>, Vec<f32>) {
        let t = varmap_tensors(varmap).unwrap();
        let tensor = |name: &str| candle_core::Tensor::new(t[name].1.as_slice(), &candle_core::Device::Cpu).unwrap();
        let z = read.broadcast_mul(&tensor("spectral.scale")).unwrap().broadcast_add(&tensor("spectral.shift")).unwrap();
        (z.mean(0).unwrap().to_vec1().unwrap(), z.sqr().unwrap().mean(0).unwrap().to_vec1().unwrap())
    };
    let (mean, square) = moments(&varmap);
    assert!(mean.iter().all(|m| m.abs() < 1e-3) && square.iter().all(|v| (v - 1.0).abs() < 1e-2), "{mean:?} {square:?}");
    let (mean, square) = moments(&checkpoint::load(&dense).unwrap().2);
    assert!(mean.iter().zip(&square).any(|(m, v)| m.abs() > 0.1 || (v - 1.0).abs() > 0.1), "the parent's: {mean:?} {square:?}");
    std::fs::remove_dir_all(dense).unwrap();
    std::fs::remove_dir_all(pruned).unwrap();
}
