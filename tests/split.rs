//! No test touch reaches training, model selection, normalisation, pruning, calibration or the
//! window's shape: a run records the split it trained on, and every path that reads its data again
//! (eval, prune, resume, distillation, the pooled stopping rule, a joint partner) reads that split
//! or refuses, on a set with a fold array, one without, and one with levels held out.

use std::path::{Path, PathBuf};

use ndarray::{Array1, Array3};
use ndarray_npy::NpzWriter;
use pvt3_trainer::data::{Dataset, TEST_FOLD};
use serde_json::Value;

#[path = "support/pvt3_command.rs"]
mod pvt3_command;
#[path = "support/workspace.rs"]
mod workspace;

use pvt3_command::{fails, ok, scratch, succeeds};

fn refs(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}

fn json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))).unwrap()
}

/// A small model of 8 tokens of 4 frames, quick to train.
const SMALL: [&str; 8] = ["--set", "space_depth=1", "--set", "time_depth=1", "--set", "tubelet=4", "--batch-size", "8"];

/// 36 touches of 3 classes and 4 channels, 12 a class: half of each class's touches `slow`, 32
/// frames long, half `fast`, 24 frames (condition `speed`); `offset` shifts every reading (another
/// sensor's view of the same touches), `folds` writes a fold array.
fn speed_set(path: &Path, offset: f32, folds: bool) -> PathBuf {
    let (n, channels, frames) = (36, 4, 32);
    let fast = |i: usize| (i / 3) % 2 == 1;
    let mut state = 11u64;
    let mut noise = move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 40) as f32 / (1u64 << 24) as f32 - 0.5
    };
    let x = Array3::from_shape_fn((n, channels, frames), |(i, c, t)| {
        let class = (i % 3) as f32;
        offset + 10.0 * c as f32 + 3.0 * class + (0.4 * (class + 1.0) * t as f32 + c as f32).sin() + noise()
    });
    let mut w = NpzWriter::new(std::fs::File::create(path).unwrap());
    w.add_array("x", &x).unwrap();
    w.add_array("y", &Array1::from_iter((0..n).map(|i| (i % 3) as i64))).unwrap();
    w.add_array("lengths", &Array1::from_iter((0..n).map(|i| if fast(i) { 24i64 } else { 32 }))).unwrap();
    let text = |s: String| Array1::from_iter(s.into_bytes());
    w.add_array("conditions", &text("speed\n".into())).unwrap();
    w.add_array("condition_speed", &text((0..n).map(|i| if fast(i) { "fast\n" } else { "slow\n" }).collect())).unwrap();
    if folds {
        w.add_array("fold", &Array1::from_iter((0..n).map(|i| ((i / 3) % 5) as i64))).unwrap();
    }
    w.finish().unwrap();
    path.to_path_buf()
}

/// The recorded split of the checkpoint `dir`: the seed that drew it, each touch's fold.
fn recorded(dir: &Path) -> (Option<u64>, Vec<usize>) {
    let trained_on = &json(&dir.join("provenance.json"))["trained_on"];
    let folds = trained_on["folds"].as_str().expect("the run records its folds").chars().map(|c| c.to_digit(10).unwrap() as usize);
    (trained_on["fold_seed"].as_u64(), folds.collect())
}

/// `pvt3 eval RUN`'s touches and accuracy on the test fold, which must be the run's own.
fn eval_agrees(run: &Path, folds: &[usize]) {
    let stdout = ok(&["eval", run.to_str().unwrap()]);
    let tests = folds.iter().filter(|f| **f == TEST_FOLD).count();
    let accuracy = json(&run.join("result.json"))["test_accuracy"].as_f64().unwrap();
    assert!(stdout.contains(&format!("{tests} samples (fold 4")), "eval reads the run's {tests} test touches: {stdout}");
    assert!(stdout.contains(&format!("accuracy {accuracy:.4}")), "eval agrees with the run's {accuracy}: {stdout}");
}

/// A set without a fold array: each seed of a cross-validation draws its own folds, the run
/// records them, and eval, prune, resume and distillation read them or refuse.
#[test]
fn each_seed_draws_its_folds_and_every_reload_reads_them() {
    let dir = scratch("seeds");
    let data = speed_set(&dir.join("set.npz"), 100.0, false);
    let (d, cv) = (data.to_str().unwrap(), dir.join("cv"));
    let mut args = vec!["cv", "--data", d, "--out", cv.to_str().unwrap(), "--epochs", "2", "--only", "seed=1,fold=0"];
    args.extend(SMALL);
    ok(&args);
    let run = cv.join("seed1/fold0");
    let (drawn, other) = (Dataset::load(&data, 1).unwrap(), Dataset::load(&data, 0).unwrap());
    assert_ne!(drawn.folds, other.folds, "the seeds' folds differ, so the checks below mean something");
    // Its normalisation is fitted on seed 1's training touches, and eval reads seed 1's test fold.
    let folds = drawn.folds.clone();
    let train: Vec<usize> = (0..folds.len()).filter(|&i| folds[i] != 0 && folds[i] != TEST_FOLD).collect();
    let fitted = pvt3_trainer::data::normalization::fit(&drawn, &train, 24);
    let norm: pvt3_trainer::data::normalization::Normalization = serde_json::from_value(json(&run.join("model/normalization.json"))).unwrap();
    assert_eq!(norm, fitted, "the normalisation of seed 1's training touches");
    eval_agrees(&run, &folds);
    assert_eq!(recorded(&run.join("model")), (Some(1), folds.clone()), "seed 1's run records seed 1's folds");

    // Pruning fine-tunes on the parent's split.
    let pruned = dir.join("pruned");
    ok(&["prune", run.to_str().unwrap(), "--prune-channels", "50", "--fine-tune-epochs", "1", "-o", pruned.to_str().unwrap()]);
    assert_eq!(recorded(&pruned.join("model")), (Some(1), folds.clone()));
    eval_agrees(&pruned, &folds);

    // Other touches are refused by name.
    let elsewhere = speed_set(&dir.join("other.npz"), 50.0, false);
    let err = fails(&["eval", run.to_str().unwrap(), "--data", elsewhere.to_str().unwrap()]);
    assert!(err.contains("not the data the run trained on"), "{err}");

    // Resumed with another seed's folds: refused, naming the seeds; with the run's own, it goes on.
    let resumed = dir.join("resumed");
    let r = resumed.to_str().unwrap();
    let mut train = vec!["train", "--data", d, "--out", r, "--epochs", "2", "--seed", "1"];
    train.extend(SMALL);
    ok(&[&train[..], &["--pause-after", "1"]].concat());
    let without_seed: Vec<&str> = train.iter().copied().filter(|a| *a != "--seed" && *a != "1").collect();
    let err = fails(&[&without_seed[..], &["--resume"]].concat());
    assert!(err.contains("trained on another split") && err.contains("drawn with seed 1, these were drawn with seed 0"), "{err}");
    ok(&[&train[..], &["--resume"]].concat());
    assert_eq!(recorded(&resumed.join("model")).1, drawn.folds);

    // Teachers trained on another split than the student's are refused.
    let student = dir.join("student");
    let mut distill = vec!["train", "--data", d, "--out", student.to_str().unwrap(), "--epochs", "1", "--fold", "0"];
    distill.extend(["--distill", cv.to_str().unwrap()]);
    distill.extend(SMALL);
    let err = fails(&distill);
    assert!(err.contains("trained on another split than this run's"), "{err}");
    std::fs::remove_dir_all(dir).unwrap();
}

/// A set with a fold array: the run records the file's folds, whatever its seed.
#[test]
fn a_fold_array_is_the_split_whatever_the_seed() {
    let dir = scratch("file");
    let data = speed_set(&dir.join("set.npz"), 100.0, true);
    let run = dir.join("run");
    let mut args = vec!["train", "--data", data.to_str().unwrap(), "--out", run.to_str().unwrap(), "--epochs", "1", "--seed", "3"];
    args.extend(SMALL);
    ok(&args);
    assert_eq!(recorded(&run.join("model")), (None, Dataset::load(&data, 0).unwrap().folds));
    eval_agrees(&run, &Dataset::load(&data, 0).unwrap().folds);
    // A run of a pvt3 that recorded no split still loads, its folds derived again, and says so.
    let provenance = run.join("model/provenance.json");
    let mut older = json(&provenance);
    older.as_object_mut().unwrap().remove("trained_on");
    std::fs::write(&provenance, older.to_string()).unwrap();
    let stderr = String::from_utf8_lossy(&succeeds(&["eval", run.to_str().unwrap()]).stderr).to_string();
    assert!(stderr.contains("records no split: its folds are derived again"), "{stderr}");
    eval_agrees(&run, &Dataset::load(&data, 0).unwrap().folds);
    std::fs::remove_dir_all(dir).unwrap();
}

/// Levels held out: the window comes from the touches that train and validate, the shorter
/// held-out touches are answered from the tokens they fill, and the pooled stopping rule reads
/// each run's own validation fold, never a held-out touch.
#[test]
fn held_out_touches_shape_and_calibrate_nothing() {
    let dir = scratch("held");
    let data = speed_set(&dir.join("set.npz"), 100.0, false);
    let (d, cv) = (data.to_str().unwrap(), dir.join("cv"));
    let mut args = vec!["cv", "--data", d, "--out", cv.to_str().unwrap(), "--epochs", "2", "--jobs", "2", "--hold-out", "speed=fast"];
    args.extend(SMALL);
    let stderr = String::from_utf8_lossy(&succeeds(&args).stderr).to_string();
    let mut validated = 0;
    for fold in 0..4 {
        let run = cv.join(format!("seed0/fold{fold}"));
        assert_eq!(json(&run.join("model/config.json"))["frames"], 32, "the window of the touches that train");
        let (_, folds) = recorded(&run.join("model"));
        for (i, f) in folds.iter().enumerate() {
            assert_eq!(*f == TEST_FOLD, (i / 3) % 2 == 1, "touch {i}: tested if and only if fast");
        }
        validated += folds.iter().filter(|f| **f == fold).count();
        eval_agrees(&run, &folds);
    }
    let stopping = &json(&cv.join("cv.json"))["stopping"];
    assert_eq!(
        stopping["calibrated_on"]["cross_validation"]["samples"], validated,
        "the runs' validation touches, and no other: {stopping}"
    );
    assert!(stderr.contains("18 test touches are shorter than the window of 32 frames"), "{stderr}");
    // The provisional answers of the short test touches, as a robot's stream gives them.
    let stdout = ok(&["eval", cv.join("seed0/fold0").to_str().unwrap(), "--anytime", "--json"]);
    let anytime: Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(anytime["samples"], 18);
    std::fs::remove_dir_all(dir).unwrap();
}

/// A joint partner never trains on the run's test touches: the same touches are refused, and a
/// set that records the held-out condition holds the same levels out.
#[test]
fn a_joint_partner_holds_out_what_the_run_holds_out() {
    let dir = scratch("joint");
    let (data, partner) = (speed_set(&dir.join("set.npz"), 100.0, false), speed_set(&dir.join("partner.npz"), 40.0, false));
    let (d, run) = (data.to_str().unwrap(), dir.join("run"));
    let joint = |partner: &Path| -> Vec<String> {
        let mut args = vec!["train", "--data", d, "--out", run.to_str().unwrap(), "--epochs", "1", "--hold-out", "speed=fast"];
        args.extend(["--joint", partner.to_str().unwrap(), "--joint-after", "0"]);
        args.extend(SMALL);
        args.into_iter().map(String::from).collect()
    };
    let err = fails(&refs(&joint(&data)));
    assert!(err.contains("holds the same touches as"), "{err}");
    ok(&refs(&joint(&partner)));
    let partner_model = run.join("partner/model");
    assert_eq!(json(&partner_model.join("provenance.json"))["held_out"]["levels"], serde_json::json!(["fast"]));
    for (i, f) in recorded(&partner_model).1.iter().enumerate() {
        assert_eq!(*f == TEST_FOLD, (i / 3) % 2 == 1, "partner touch {i}: tested if and only if fast");
    }
    std::fs::remove_dir_all(dir).unwrap();
}
