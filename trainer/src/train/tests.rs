//! Training on a tiny synthetic problem: it learns, a seed fixes the run, and a paused run
//! resumed gives exactly the uninterrupted result.

use std::path::PathBuf;

use candle_core::{Device, Tensor};
use indicatif::ProgressBar;
use pvt3_models::{Config, Rng};

use super::*;
use crate::data::augment::{Augmentation, Robust};
use crate::data::{Dataset, Frames};
use crate::json::read_json;
use crate::options::{Distillation, HeldZeros, Optimization, Pruning};
use crate::run_dir::{Checkpoint, CrossValidation};

fn tiny_config() -> Config {
    Config {
        height: 2,
        width: 2,
        channels: 1,
        frames: 8,
        patch_height: 1,
        patch_width: 2,
        tubelet: 2,
        dim: 8,
        space_depth: 1,
        time_depth: 1,
        heads: 2,
        dim_head: 4,
        mlp_dim: 8,
        classes: 2,
        ..Config::icub20()
    }
}

/// Two classes: a rising or a falling ramp on taxel 0, noise elsewhere, offset 50 everywhere.
pub(crate) fn tiny_data() -> Dataset {
    let mut rng = Rng::new(11);
    let (n, len) = (80, 2 * 2 * 8);
    let mut x = Vec::with_capacity(n * len);
    let labels: Vec<u32> = (0..n as u32).map(|i| i % 2).collect();
    for &label in &labels {
        for taxel in 0..4 {
            for t in 0..8 {
                let ramp = if label == 0 { t as f32 } else { 7.0 - t as f32 };
                let signal = if taxel == 0 { ramp } else { 0.0 };
                x.push(50.0 + signal + rng.normal());
            }
        }
    }
    let folds = (0..n).map(|i| (i / 2) % 5).collect();
    Dataset { folds, path: PathBuf::from("tiny"), ..Dataset::in_memory(x, vec![2, 2, 8], labels) }
}

fn options(epochs: usize) -> TrainOptions {
    TrainOptions {
        optimization: Optimization {
            epochs,
            batch_size: 8,
            lr: 5e-3,
            lr_floor: 0.01,
            warmup_epochs: 1,
            weight_decay: 0.01,
            label_smoothing: 0.1,
            clip_grad: 1.0,
            patience: None,
        },
        augmentation: Augmentation {
            gain: 0.1,
            noise: 0.05,
            shift: 0,
            scale: 0.0,
            channel_scale: 0.0,
            vibration: 0.0,
            stretch: 0.0,
            reverse: 0.0,
            translate: 0,
            flip: 0.0,
            mixup: 0.0,
            extrapolate: 0.0,
            extrapolate_levels: false,
            robust: Robust::Off,
        },
        ema: 0.0,
        seed: 5,
        pruning: Pruning { l1: 0.0, mask_lr: 1.0, random_prune: 0.0 },
        prefix_training: 0.0,
        distillation: Distillation { teachers: None, weight: 1.0 },
        joint: None,
        camera_head: None,
        held: HeldZeros::default(),
    }
}

/// `options(epochs)` changed by `change`.
fn options_with(epochs: usize, change: impl FnOnce(&mut TrainOptions)) -> TrainOptions {
    let mut options = options(epochs);
    change(&mut options);
    options
}

pub(crate) fn out_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pvt3-train-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

pub(crate) fn spec(data: &Dataset, epochs: usize, pause_after: Option<usize>) -> RunSpec<'_> {
    RunSpec {
        data,
        config: tiny_config(),
        val_fold: Some(0),
        options: options(epochs),
        classes: vec!["up".into(), "down".into()],
        pause_after,
        start: None,
        pruning: None,
        partner: None,
    }
}

/// The metrics log without the timings.
fn metrics(dir: &std::path::Path) -> Vec<serde_json::Value> {
    std::fs::read_to_string(dir.join("metrics.jsonl"))
        .unwrap()
        .lines()
        .map(|l| {
            let mut v: serde_json::Value = serde_json::from_str(l).unwrap();
            v.as_object_mut().unwrap().remove("seconds");
            v
        })
        .collect()
}

#[test]
fn learns_a_separable_problem_and_writes_a_checkpoint() {
    let data = tiny_data();
    let dir = out_dir("learn");
    let r = train(&spec(&data, 30, None), &dir, false, &ProgressBar::hidden()).unwrap().unwrap();
    assert!(r.test_accuracy >= 0.9, "{r:?}");
    assert_eq!(metrics(&dir).len(), 30);
    let (mut meta, model, _) = crate::checkpoint::load(&dir).unwrap();
    assert_eq!(meta.classes, vec!["up", "down"]);
    assert_eq!(meta.provenance.epoch, r.best_epoch);
    let split = data.split(0).unwrap();
    assert_eq!(meta.normalization, crate::data::normalization::fit(&data, &split.train, 8), "fitted on the training split only");
    // The stopping rule calibrated on the validation fold, and found again for a run without one.
    let pvt3 = crate::anytime::answering(&model).unwrap();
    let carried = meta.provenance.stopping.clone().expect("calibrated");
    assert_eq!(crate::anytime::carried_rule(pvt3, &meta, &data).unwrap(), carried);
    meta.provenance.stopping = None;
    assert_eq!(crate::anytime::carried_rule(pvt3, &meta, &data).unwrap(), carried, "calibrated as training calibrates");
    let again = train(&spec(&data, 30, None), &dir, false, &ProgressBar::hidden()).unwrap_err().to_string();
    assert!(again.contains("already holds a run; pass --resume"), "{again}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_seed_fixes_the_run_and_a_paused_run_resumes_exactly() {
    let data = tiny_data();
    let (a, b) = (out_dir("a"), out_dir("b"));
    let ra = train(&spec(&data, 6, None), &a, false, &ProgressBar::hidden()).unwrap().unwrap();
    assert!(train(&spec(&data, 6, Some(2)), &b, false, &ProgressBar::hidden()).unwrap().is_none());
    assert_eq!(metrics(&b).len(), 2);
    let rb = train(&spec(&data, 6, None), &b, true, &ProgressBar::hidden()).unwrap().unwrap();
    assert_eq!((ra.best_epoch, ra.val_accuracy, ra.test_accuracy), (rb.best_epoch, rb.val_accuracy, rb.test_accuracy));
    assert_eq!(metrics(&a), metrics(&b));
    let weights = |d: &PathBuf| std::fs::read(d.join("model/weights.safetensors")).unwrap();
    assert_eq!(weights(&a), weights(&b), "identical weights, bit for bit");
    let done = train(&spec(&data, 6, None), &b, true, &ProgressBar::hidden()).unwrap().unwrap();
    assert_eq!(done, rb, "resuming a finished run returns its result");
    std::fs::remove_dir_all(a).unwrap();
    std::fs::remove_dir_all(b).unwrap();
}

/// Trains `options` for `epochs` twice, once paused after 2 epochs and resumed: the two must
/// agree bit for bit. Returns the uninterrupted run's directory.
fn resumes_exactly(tag: &str, data: &Dataset, options: TrainOptions) -> PathBuf {
    resumes_exactly_as(tag, &RunSpec { options: options.clone(), ..spec(data, options.optimization.epochs, None) })
}

/// [`resumes_exactly`] for any run: `base` trained twice, once paused after 2 epochs and resumed;
/// the two agree bit for bit, and so do their partners' (`--joint`).
fn resumes_exactly_as(tag: &str, base: &RunSpec) -> PathBuf {
    let with = |pause| RunSpec { pause_after: pause, ..base.clone() };
    let (a, b) = (out_dir(&format!("{tag}-a")), out_dir(&format!("{tag}-b")));
    train(&with(None), &a, false, &ProgressBar::hidden()).unwrap().unwrap();
    assert!(train(&with(Some(2)), &b, false, &ProgressBar::hidden()).unwrap().is_none());
    train(&with(None), &b, true, &ProgressBar::hidden()).unwrap().unwrap();
    let weights = |d: &PathBuf| std::fs::read(d.join("model/weights.safetensors")).unwrap();
    let mut compared = vec![(a.clone(), b.clone())];
    compared.extend(base.partner.as_ref().map(|_| (Run(&a).partner(), Run(&b).partner())));
    for (a, b) in &compared {
        assert_eq!(metrics(a), metrics(b), "{tag}: {}", a.display());
        assert_eq!(weights(a), weights(b), "{tag}: identical weights of {}, bit for bit", a.display());
    }
    std::fs::remove_dir_all(b).unwrap();
    a
}

/// Training on prefixes draws from the run's own generator: a paused run still resumes bit for
/// bit, the run differs from one on whole windows, and the finished run carries a calibrated
/// stopping rule.
#[test]
fn prefix_training_resumes_exactly_and_calibrates_a_stopping_rule() {
    let data = tiny_data();
    let a = resumes_exactly("prefix", &data, TrainOptions { prefix_training: 0.5, ..options(4) });
    let whole = out_dir("prefix-whole");
    train(&spec(&data, 4, None), &whole, false, &ProgressBar::hidden()).unwrap().unwrap();
    assert_ne!(metrics(&a), metrics(&whole), "prefixes change the training");
    let (_, meta) = crate::checkpoint::load_meta(&a).unwrap();
    let stopping = meta.provenance.stopping.expect("a calibrated stopping rule");
    assert!(stopping.rule.problem().is_none() && stopping.mean_share <= 1.0, "{stopping:?}");
    assert!(stopping.accuracy >= stopping.full_accuracy - 1e-12, "no accuracy lost on the validation fold: {stopping:?}");
    for d in [a, whole] {
        std::fs::remove_dir_all(d).unwrap();
    }
}

/// The weight average is what is selected and saved, and its state resumes bit for bit.
#[test]
fn weight_averaging_resumes_exactly_and_checkpoints_the_average() {
    let data = tiny_data();
    let a = resumes_exactly("ema", &data, TrainOptions { ema: 0.9, ..options(5) });
    assert!(Checkpoint(&Run(&a).last()).average().exists());
    let raw = out_dir("ema-raw");
    train(&spec(&data, 5, None), &raw, false, &ProgressBar::hidden()).unwrap().unwrap();
    let weights = |d: &PathBuf, w: &str| std::fs::read(d.join(w).join("weights.safetensors")).unwrap();
    assert_eq!(weights(&a, "last"), weights(&raw, "last"), "averaging leaves the raw weights' training alone");
    let val_losses = |d: &PathBuf| metrics(d).iter().map(|m| m["val_loss"].as_f64().unwrap()).collect::<Vec<_>>();
    assert_ne!(val_losses(&a), val_losses(&raw), "the average is what is evaluated");
    for d in [a, raw] {
        std::fs::remove_dir_all(d).unwrap();
    }
}

/// Same-class extrapolation draws from the run's own generator too: a run resumes bit for bit.
#[test]
fn extrapolation_resumes_exactly() {
    let dir = resumes_exactly("extrapolate", &tiny_data(), options_with(4, |o| o.augmentation.extrapolate = 0.5));
    std::fs::remove_dir_all(dir).unwrap();
}

/// Distillation: runs of the same split teach, a taught run resumes bit for bit and differs from
/// one untaught; teachers of another split, none for the run's fold, the run itself or a run
/// still training are refused by name.
#[test]
fn distillation_learns_from_runs_of_the_same_split_and_resumes_exactly() {
    let data = tiny_data();
    let teachers = out_dir("teachers");
    for seed in [0, 1] {
        let options = TrainOptions { seed, ..options(3) };
        let run = RunSpec { options, ..spec(&data, 3, None) };
        train(&run, &CrossValidation(&teachers).run(seed, 0), false, &ProgressBar::hidden()).unwrap().unwrap();
    }
    let taught = options_with(4, |o| o.distillation = Distillation { teachers: Some(teachers.display().to_string()), weight: 2.0 });
    let a = resumes_exactly("distill", &data, taught.clone());
    let alone = out_dir("distill-alone");
    train(&spec(&data, 4, None), &alone, false, &ProgressBar::hidden()).unwrap().unwrap();
    assert_ne!(metrics(&a), metrics(&alone), "the teachers change the training");

    let refused = |val_fold: usize, data: &Dataset, tag: &str| {
        let run = RunSpec { val_fold: Some(val_fold), options: taught.clone(), ..spec(data, 4, None) };
        train(&run, &out_dir(tag), false, &ProgressBar::hidden()).unwrap_err().to_string()
    };
    let none = refused(1, &data, "distill-fold1");
    assert!(none.contains("no trained run of validation fold 1") && none.contains(&teachers.display().to_string()), "{none}");
    let mut other = tiny_data();
    let Frames::F32(x) = std::sync::Arc::make_mut(&mut other.x) else { unreachable!("tiny data are f32") };
    x.iter_mut().for_each(|v| *v += 1.0);
    let elsewhere = refused(0, &other, "distill-other");
    assert!(elsewhere.contains("trained on another split") && elsewhere.contains("seed0/fold0"), "{elsewhere}");
    let own = RunSpec { options: taught.clone(), ..spec(&data, 4, None) };
    let itself = train(&own, &teachers.join("seed1/fold0/pruned"), false, &ProgressBar::hidden()).unwrap_err().to_string();
    assert!(itself.contains("cannot teach itself") && itself.contains("seed1/fold0"), "{itself}");
    std::fs::remove_file(Run(&teachers.join("seed0/fold0")).result()).unwrap();
    let unfinished = refused(0, &data, "distill-unfinished");
    assert!(unfinished.contains("still training") && unfinished.contains("seed0/fold0"), "{unfinished}");
    for d in [a, alone, teachers] {
        std::fs::remove_dir_all(d).unwrap();
    }
}

/// Mixup draws from the run's own generator too, and still learns the tiny problem.
#[test]
fn mixup_learns_and_resumes_exactly() {
    let data = tiny_data();
    let a = resumes_exactly("mixup", &data, options_with(4, |o| o.augmentation.mixup = 0.4));
    std::fs::remove_dir_all(a).unwrap();
    let dir = out_dir("mixup-learn");
    let r = train(
        &RunSpec { options: options_with(30, |o| o.augmentation.mixup = 0.4), ..spec(&data, 30, None) },
        &dir,
        false,
        &ProgressBar::hidden(),
    )
    .unwrap()
    .unwrap();
    assert!(r.test_accuracy >= 0.9, "{r:?}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_run_gives_the_same_bits_on_one_thread_or_three() {
    let data = tiny_data();
    let run = |threads: usize| {
        let dir = out_dir(&format!("threads{threads}"));
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let result = pool.install(|| train(&spec(&data, 3, None), &dir, false, &ProgressBar::hidden())).unwrap().unwrap();
        let weights = std::fs::read(dir.join("model/weights.safetensors")).unwrap();
        std::fs::remove_dir_all(dir).unwrap();
        ((result.best_epoch, result.val_accuracy, result.test_accuracy), weights)
    };
    assert_eq!(run(1), run(3));
}

#[test]
fn random_pruning_regularises_without_leaving_zeros_behind() {
    let data = tiny_data();
    let dir = out_dir("random-prune");
    let mut s = spec(&data, 30, None);
    s.options.pruning.random_prune = 0.05;
    let r = train(&s, &dir, false, &ProgressBar::hidden()).unwrap().unwrap();
    // A width-8 model is fragile: 5 % of its weights gone each step costs accuracy, but it learns.
    assert!(r.test_accuracy >= 0.75, "{r:?}");
    let (_, _, varmap) = crate::checkpoint::load(&dir).unwrap();
    let vars = varmap.data().lock().unwrap();
    let w = vars["space.layers.0.ffn.fc1.weight"].flatten_all().unwrap().to_vec1::<f32>().unwrap();
    assert!(w.iter().all(|v| *v != 0.0), "the pruned entries are restored after every step");
    std::fs::remove_dir_all(dir).unwrap();
}

/// A second tiny sensor touching the same two classes: 3 × 1 taxels, the ramp on the middle one,
/// its touches in another order than [`tiny_data`]'s.
fn tiny_other_sensor() -> (Dataset, Config) {
    let mut rng = Rng::new(12);
    let n = 60;
    let labels: Vec<u32> = (0..n as u32).map(|i| (i / 3) % 2).collect();
    let mut x = Vec::new();
    for &label in &labels {
        for taxel in 0..3 {
            for t in 0..8 {
                let ramp = if label == 0 { t as f32 } else { 7.0 - t as f32 };
                x.push(20.0 + if taxel == 1 { 2.0 * ramp } else { 0.0 } + rng.normal());
            }
        }
    }
    let data = Dataset { path: PathBuf::from("tiny-other"), folds: tiny_data().folds, ..Dataset::in_memory(x, vec![3, 1, 8], labels) };
    (data, Config { height: 3, width: 1, patch_height: 3, patch_width: 1, ..tiny_config() })
}

fn joint_spec<'a>(data: &'a Dataset, other: &'a (Dataset, Config), epochs: usize, weight: f64) -> RunSpec<'a> {
    let joint = crate::options::Joint { partner: "tiny-other".into(), weight, after_epochs: 2, share_temporal: false };
    RunSpec {
        options: TrainOptions { joint: Some(joint), ..options(epochs) },
        partner: Some(Partner { data: &other.0, config: other.1.clone(), classes: vec!["up".into(), "down".into()] }),
        ..spec(data, epochs, None)
    }
}

/// A joint run trains the other sensor's network beside, into `partner/`, each validated on its
/// own sensor; both resume bit for bit; the encodings' error changes training only from the
/// epoch after `after_epochs`, and the partner's provenance names this run's data as its partner.
#[test]
fn a_joint_run_trains_both_sensors_and_resumes_exactly() {
    let (data, other) = (tiny_data(), tiny_other_sensor());
    let a = resumes_exactly_as("joint", &joint_spec(&data, &other, 12, 1.0));
    let partner = Run(&a).partner();
    let result: RunResult = read_json(&Run(&partner).result()).unwrap();
    assert!(result.test_accuracy >= 0.9, "the other sensor learns its touches: {result:?}");
    let (_, meta) = crate::checkpoint::load_meta(&partner).unwrap();
    assert_eq!(meta.provenance.data, "tiny-other");
    assert_eq!(meta.provenance.options.joint.as_ref().unwrap().partner, "tiny");
    assert_eq!(meta.config.height, 3);
    assert_eq!(metrics(&partner).len(), 12);
    let apart = |d: &PathBuf| metrics(d).iter().map(|m| m["encodings_apart"].as_f64().expect("measured every epoch")).collect::<Vec<_>>();
    assert_eq!(apart(&a), apart(&partner), "one distance, in both logs");
    assert!(apart(&a)[11] < apart(&a)[1], "pulled together: {:?}", apart(&a));
    assert!(metrics(&a).len() == 12 && learnt_alone_has_no_distance(&data));
    // Without the encodings' error (weight 0) the first two epochs are the same, then not.
    let apart = out_dir("joint-apart");
    train(&joint_spec(&data, &other, 3, 0.0), &apart, false, &ProgressBar::hidden()).unwrap().unwrap();
    let pulled = out_dir("joint-pulled");
    train(&joint_spec(&data, &other, 3, 1.0), &pulled, false, &ProgressBar::hidden()).unwrap().unwrap();
    let (m0, m1) = (metrics(&apart), metrics(&pulled));
    assert_eq!(m0[..2], m1[..2]);
    assert_ne!(m0[2]["train_loss"], m1[2]["train_loss"]);
    for d in [a, apart, pulled] {
        std::fs::remove_dir_all(d).unwrap();
    }
}

/// Joint learning refuses what it cannot pair or compare, naming the other data set.
#[test]
fn a_joint_run_refuses_encodings_of_other_widths_other_classes_mixup_and_distillation() {
    let (data, other) = (tiny_data(), tiny_other_sensor());
    let refused = |spec: RunSpec| train(&spec, &out_dir("joint-refused"), false, &ProgressBar::hidden()).unwrap_err().to_string();
    let wide = (other.0.clone(), Config { dim: 12, ..other.1.clone() });
    let err = refused(joint_spec(&data, &wide, 1, 1.0));
    assert!(err.contains("--joint tiny-other") && err.contains("12 values and this one in 8"), "{err}");
    let base = joint_spec(&data, &other, 1, 1.0);
    let renamed = Partner { classes: vec!["smooth".into(), "rough".into()], ..base.partner.clone().unwrap() };
    let err = refused(RunSpec { partner: Some(renamed), ..base.clone() });
    assert!(err.contains("pairs are made by class"), "{err}");
    let err = refused(RunSpec {
        options: TrainOptions { augmentation: Augmentation { mixup: 0.2, ..base.options.augmentation.clone() }, ..base.options.clone() },
        ..base.clone()
    });
    assert!(err.contains("--mixup"), "{err}");
    let err = refused(RunSpec {
        options: TrainOptions { distillation: Distillation { teachers: Some("runs/any".into()), weight: 1.0 }, ..base.options.clone() },
        ..base
    });
    assert!(err.contains("--joint tiny-other") && err.contains("--distill"), "{err}");
}

/// With a shared temporal transformer the two networks hold one set of its weights, updated once
/// a step with both losses' gradients (the partner's optimiser has none of them), and still
/// resume bit for bit.
#[test]
fn a_joint_run_sharing_the_temporal_transformer_holds_one_copy_and_resumes_exactly() {
    let (data, other) = (tiny_data(), tiny_other_sensor());
    let mut spec = joint_spec(&data, &other, 4, 1.0);
    spec.options.joint.as_mut().unwrap().share_temporal = true;
    let a = resumes_exactly_as("joint-shared", &spec);
    let load = |p: PathBuf| candle_core::safetensors::load(p, &Device::Cpu).unwrap();
    let last = Run(&a).last();
    let (own, partner) = (load(Checkpoint(&last).weights()), load(Checkpoint(&Checkpoint(&last).partner()).weights()));
    let temporal: Vec<&String> = own.keys().filter(|k| k.starts_with("temporal.")).collect();
    assert!(!temporal.is_empty());
    for name in temporal {
        assert_eq!(flat_of(&own, name), flat_of(&partner, name), "{name}: one copy");
    }
    assert_ne!(flat_of(&own, "head.weight"), flat_of(&partner, "head.weight"), "each its own head");
    let moments = load(Checkpoint(&Checkpoint(&last).partner()).optimizer());
    assert!(moments.keys().all(|k| !k.contains(".temporal.")) && !moments.is_empty(), "the partner's optimiser leaves them alone");
    // Without sharing, the two transformers differ after training.
    let apart = out_dir("joint-unshared");
    train(&joint_spec(&data, &other, 4, 1.0), &apart, false, &ProgressBar::hidden()).unwrap().unwrap();
    let last = Run(&apart).last();
    let (own, partner) = (load(Checkpoint(&last).weights()), load(Checkpoint(&Checkpoint(&last).partner()).weights()));
    assert_ne!(flat_of(&own, "temporal.layers.0.ffn.fc1.weight"), flat_of(&partner, "temporal.layers.0.ffn.fc1.weight"));
    for d in [a, apart] {
        std::fs::remove_dir_all(d).unwrap();
    }
}

fn flat_of(tensors: &std::collections::HashMap<String, Tensor>, name: &str) -> Vec<f32> {
    tensors.get(name).unwrap_or_else(|| panic!("no {name} among {:?}", tensors.keys())).flatten_all().unwrap().to_vec1::<f32>().unwrap()
}

/// A run of one sensor logs no encodings' distance.
fn learnt_alone_has_no_distance(data: &Dataset) -> bool {
    let dir = out_dir("alone-no-distance");
    train(&spec(data, 1, None), &dir, false, &ProgressBar::hidden()).unwrap().unwrap();
    let none = metrics(&dir).iter().all(|m| m.get("encodings_apart").is_none());
    std::fs::remove_dir_all(dir).unwrap();
    none
}

/// The spectral head's standardisation is fitted before the first step and held there, while
/// its linear map trains: after one epoch and after four they are the same bits.
#[test]
fn the_spectral_standardisation_stays_where_it_was_fitted() {
    let data = tiny_data();
    let config = Config { network: pvt3_models::Pvt3Config { spectral_bands: 2, ..Default::default() }.into(), ..tiny_config() };
    let run = RunSpec { config, ..spec(&data, 4, Some(1)) };
    let dir = out_dir("spectral-fitted");
    let load = |dir: &PathBuf| candle_core::safetensors::load(Checkpoint(&Run(dir).last()).weights(), &Device::Cpu).unwrap();
    assert!(train(&run, &dir, false, &ProgressBar::hidden()).unwrap().is_none());
    let first = load(&dir);
    train(&RunSpec { pause_after: None, ..run }, &dir, true, &ProgressBar::hidden()).unwrap().unwrap();
    let last = load(&dir);
    for name in ["spectral.scale", "spectral.shift"] {
        assert_eq!(flat_of(&first, name), flat_of(&last, name), "{name}: fitted, not trained");
    }
    assert_ne!(flat_of(&first, "spectral.scale"), vec![1.0; 4 * 3], "fitted to the training windows");
    assert_ne!(flat_of(&first, "spectral.linear.weight"), flat_of(&last, "spectral.linear.weight"), "the map trains");
    std::fs::remove_dir_all(dir).unwrap();
}

/// A spectral head over the image's space has its whole map fitted before the first step (a
/// logistic regression from zero, whose two classes' rows are each other's negatives, as no
/// random start's are) and held there while the network trains beside it.
#[test]
fn a_head_over_the_image_is_fitted_and_held() {
    let data = tiny_data();
    let network = pvt3_models::Pvt3Config { spectral_bands: 2, spectral_space: true, ..Default::default() };
    let run = RunSpec { config: Config { network: network.into(), ..tiny_config() }, ..spec(&data, 4, Some(1)) };
    let dir = out_dir("spectral-space-fitted");
    let load = |dir: &PathBuf| candle_core::safetensors::load(Checkpoint(&Run(dir).last()).weights(), &Device::Cpu).unwrap();
    assert!(train(&run, &dir, false, &ProgressBar::hidden()).unwrap().is_none());
    let first = load(&dir);
    train(&RunSpec { pause_after: None, ..run }, &dir, true, &ProgressBar::hidden()).unwrap().unwrap();
    let last = load(&dir);
    for name in ["spectral.scale", "spectral.shift", "spectral.linear.weight", "spectral.linear.bias"] {
        assert_eq!(flat_of(&first, name), flat_of(&last, name), "{name}: fitted, not trained");
    }
    let (weight, bias) = (flat_of(&first, "spectral.linear.weight"), flat_of(&first, "spectral.linear.bias"));
    let features = weight.len() / 2;
    assert!(weight[..features].iter().zip(&weight[features..]).all(|(a, b)| (a + b).abs() < 1e-6), "{weight:?}");
    assert!((bias[0] + bias[1]).abs() < 1e-6 && weight.iter().any(|w| w.abs() > 1e-3), "{weight:?} {bias:?}");
    assert_ne!(flat_of(&first, "patch_embed.weight"), flat_of(&last, "patch_embed.weight"), "the network trains");
    std::fs::remove_dir_all(dir).unwrap();
}

/// `--patience` ends a run once validation has stalled that long: every epoch until then is the
/// run's without it, the result counts the epochs trained, and a paused run stops where it would.
#[test]
fn patience_stops_a_run_whose_validation_stalls_and_resumes_exactly() {
    let data = tiny_data();
    let dir = resumes_exactly("patience", &data, options_with(30, |o| o.optimization.patience = Some(2)));
    let r: RunResult = read_json(&Run(&dir).result()).unwrap();
    let trained = metrics(&dir);
    assert!(trained.len() < 30, "stopped: {r:?}");
    assert_eq!((r.epochs, trained.len()), (r.best_epoch + 2, r.best_epoch + 2), "{r:?}");
    let every = out_dir("patience-every");
    let all = train(&spec(&data, 30, None), &every, false, &ProgressBar::hidden()).unwrap().unwrap();
    assert_eq!(all.epochs, 30);
    assert_eq!(metrics(&every)[..trained.len()], trained[..], "the same epochs until the stop");
    std::fs::remove_dir_all(dir).unwrap();
    std::fs::remove_dir_all(every).unwrap();
}
