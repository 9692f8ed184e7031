//! End-to-end tests of the `pvt3` command on a small slice of the shipped iCub data: train,
//! evaluate, cross-validate (side by side and resumed), inspect, and the errors a user meets.

use std::path::{Path, PathBuf};
use std::process::Command;

use ndarray::{Array1, ArrayD, IxDyn};
use ndarray_npy::NpzWriter;
use pvt3_trainer::data::Dataset;

#[path = "support/csv_tree.rs"]
mod csv_tree;
#[path = "support/onnx_check.rs"]
mod onnx_check;
#[path = "support/pvt3_command.rs"]
mod pvt3_command;
#[path = "support/workspace.rs"]
mod workspace;

use pvt3_command::{fails, ok, pvt3, scratch, succeeds};

/// The first `per_fold` samples of every fold of the shipped iCub set, as an .npz.
fn icub_slice(dir: &Path, per_fold: usize) -> PathBuf {
    slice("icub20", dir, per_fold, 1)
}

/// `per_fold` samples of every fold of the shipped set `name`, every `stride`-th from the first,
/// as an .npz in `dir`.
fn slice(name: &str, dir: &Path, per_fold: usize, stride: usize) -> PathBuf {
    let root = workspace::workspace().join(format!("data/{name}.npz"));
    let d = Dataset::load(&root, 0).unwrap();
    let mut picked = Vec::new();
    for f in 0..5 {
        picked.extend((0..d.len()).filter(|&i| d.folds[i] == f).step_by(stride).take(per_fold));
    }
    let x: Vec<f32> = picked.iter().flat_map(|&i| d.sample(i).to_vec()).collect();
    let mut shape = vec![picked.len()];
    shape.extend(&d.sample_shape);
    let path = dir.join(if name == "icub20" { "slice.npz".to_string() } else { format!("{name}.npz") });
    let mut w = NpzWriter::new_compressed(std::fs::File::create(&path).unwrap());
    w.add_array("x", &ArrayD::from_shape_vec(IxDyn(&shape), x).unwrap()).unwrap();
    w.add_array("y", &Array1::from_iter(picked.iter().map(|&i| d.labels[i] as i64))).unwrap();
    w.add_array("fold", &Array1::from_iter(picked.iter().map(|&i| d.folds[i] as i64))).unwrap();
    w.finish().unwrap();
    path
}

const SMALL: [&str; 6] = ["--set", "space_depth=1", "--set", "time_depth=1", "--batch-size", "16"];

#[test]
fn info_reports_the_published_size() {
    let out = ok(&["info"]);
    assert!(out.contains("parameters    64272 trainable + 75 frame-mask entries"), "{out}");
    let json = ok(&["info", "biotac20", "--json"]);
    let cfg: pvt3_models::Config = serde_json::from_str(&json).unwrap();
    assert_eq!(cfg, pvt3_models::Config::biotac20());
}

#[test]
fn train_then_eval_agree_on_the_test_accuracy() {
    let dir = scratch("train");
    let data = icub_slice(&dir, 20);
    let run = dir.join("run");
    let (d, r) = (data.to_str().unwrap(), run.to_str().unwrap());
    let mut args = vec!["train", "--data", d, "--out", r, "--epochs", "2", "--fold", "1"];
    args.extend(SMALL);
    let out = ok(&args);
    assert!(out.contains("best epoch"), "{out}");
    for f in ["config.json", "weights.safetensors", "normalization.json", "classes.json", "provenance.json"] {
        assert!(run.join("model").join(f).exists(), "{f} is in the checkpoint");
    }
    let provenance: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(run.join("model/provenance.json")).unwrap()).unwrap();
    let recorded = provenance["test_accuracy"].as_f64().unwrap();
    let eval = ok(&["eval", r, "--data", d]);
    assert!(eval.contains(&format!("accuracy {recorded:.4}")), "eval {eval} vs recorded {recorded}");
    let info = ok(&["info", &format!("{r}/model")]);
    assert!(!info.contains("64272 trainable") && info.contains("space.layers.0.attn"), "overrides are stored: {info}");

    let again = fails(&args);
    assert!(again.contains("already holds a run; pass --resume"), "{again}");
    std::fs::remove_dir_all(dir).unwrap();
}

/// Training for provisional answers: the run calibrates its stopping rule on the validation
/// fold, `eval --anytime` reports the touch share against accuracy on the run's own data, and
/// the exported file carries the rule for the runtime.
#[test]
fn prefix_training_calibrates_a_stopping_rule_that_the_file_carries() {
    let dir = scratch("anytime");
    let data = icub_slice(&dir, 12);
    let run = dir.join("run");
    let onnx = dir.join("run.onnx");
    let (d, r) = (data.to_str().unwrap(), run.to_str().unwrap());
    let mut args = vec!["train", "--data", d, "--out", r, "--epochs", "2", "--prefix-training", "0.5", "--export", onnx.to_str().unwrap()];
    args.extend(SMALL);
    ok(&args);
    let provenance: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(run.join("model/provenance.json")).unwrap()).unwrap();
    let stopping = &provenance["stopping"];
    let rule: pvt3_runtime::StopRule = serde_json::from_value(stopping["rule"].clone()).unwrap();
    assert!(rule.problem().is_none() && rule.agreeing == 3, "{stopping}");
    assert!(stopping["accuracy"].as_f64().unwrap() >= stopping["full_accuracy"].as_f64().unwrap() - 1e-12, "{stopping}");
    // The run's own data by default (no --data).
    let table = ok(&["eval", r, "--anytime"]);
    assert!(
        table.contains("provisional answers on") && table.contains("100%") && table.contains("stopping rule: top probability"),
        "{table}"
    );
    let recorded = format!("≥ {:.4} with 3 answers in a row", rule.top_probability);
    assert!(table.contains(&recorded), "the calibration training recorded: {table}");
    // And drawn: accuracy so far, and where the rule ends touches.
    let picture = std::fs::read_to_string(run.join("anytime-fold4.svg")).unwrap();
    assert!(table.contains("drew") && picture.contains("touches the rule has ended"), "{table}");
    let answers_path = dir.join("answers.json");
    let report: serde_json::Value =
        serde_json::from_str(&ok(&["eval", r, "--anytime", "--json", "--answers", answers_path.to_str().unwrap()])).unwrap();
    let curve = report["curve"].as_array().unwrap();
    assert_eq!(curve.len(), 10);
    assert_eq!(curve[9]["tokens"], 75);
    // Every sample's probabilities after each token: the curve's accuracies read from them.
    let answers: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&answers_path).unwrap()).unwrap();
    let (probabilities, labels) = (answers["probabilities"].as_array().unwrap(), answers["labels"].as_array().unwrap());
    assert_eq!(
        (probabilities.len(), labels.len(), report["samples"].as_u64().unwrap() as usize),
        (labels.len(), labels.len(), labels.len())
    );
    let argmax = |p: &serde_json::Value| {
        let p: Vec<f64> = p.as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
        assert!(p.len() == 20 && (p.iter().sum::<f64>() - 1.0).abs() < 1e-4);
        (0..p.len()).fold(0, |b, c| if p[c] > p[b] { c } else { b }) as u64
    };
    for point in curve {
        let k = point["tokens"].as_u64().unwrap() as usize;
        let right = probabilities.iter().zip(labels).filter(|(p, l)| argmax(&p[k - 1]) == l.as_u64().unwrap()).count();
        assert_eq!(right as f64 / labels.len() as f64, point["accuracy"].as_f64().unwrap(), "after {k} tokens");
    }
    let eval = ok(&["eval", r]);
    assert!(eval.contains(&format!("accuracy {:.4}", curve[9]["accuracy"].as_f64().unwrap())), "the whole touch is plain eval: {eval}");
    assert_eq!(pvt3_runtime::Classifier::load(&onnx).unwrap().stop_rule(), Some(rule));
    let err = fails(&["train", "--data", d, "--out", dir.join("v").to_str().unwrap(), "--model", "vit", "--prefix-training", "0.5"]);
    assert!(err.contains("--prefix-training: PVT³ models only"), "{err}");
    let err = fails(&["train", "--data", d, "--out", dir.join("v").to_str().unwrap(), "--prefix-training", "1.5"]);
    assert!(err.contains("--prefix-training 1.5: expected a number in [0, 1]"), "{err}");
    assert!(!dir.join("v").exists(), "refused before training");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn cv_runs_folds_side_by_side_and_resumes_without_retraining() {
    let dir = scratch("cv");
    let data = icub_slice(&dir, 12);
    let out = dir.join("cv");
    let (d, o) = (data.to_str().unwrap(), out.to_str().unwrap());
    let mut args = vec!["cv", "--data", d, "--out", o, "--epochs", "1", "--jobs", "2"];
    args.extend(SMALL);
    let first = ok(&args);
    assert!(first.contains("mean test accuracy"), "{first}");
    // One seed: no interval, and it says why and how to get one.
    assert!(first.contains("no 95 % confidence interval") && first.contains("--seeds 0,1,2"), "{first}");
    let next = format!("next: pvt3 eval {o} (all runs' test answers together");
    assert!(first.contains(&next) && first.contains(&format!("pvt3 final {o} -o model.onnx")), "{first}");
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("cv.json")).unwrap()).unwrap();
    assert_eq!(summary["runs"].as_array().unwrap().len(), 4);
    // One stopping rule, calibrated on the four runs' validation answers, in every run and in
    // the file any of them exports.
    let stopping = &summary["stopping"];
    assert_eq!(stopping["calibrated_on"], serde_json::json!({"cross_validation": {"runs": 4, "samples": 48}}), "{summary}");
    assert!(first.contains(&format!("with {} answers in a row agreeing", stopping["rule"]["agreeing"])), "{first}");
    for fold in 0..4 {
        let provenance: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join(format!("seed0/fold{fold}/model/provenance.json"))).unwrap()).unwrap();
        assert_eq!(&provenance["stopping"], stopping, "fold {fold}");
    }
    let onnx = dir.join("fold1.onnx");
    ok(&["export", out.join("seed0/fold1").to_str().unwrap(), "-o", onnx.to_str().unwrap()]);
    let carried = pvt3_runtime::Classifier::load(&onnx).unwrap().stop_rule().unwrap();
    assert_eq!(
        (carried.top_probability, carried.agreeing as u64),
        (stopping["rule"]["top_probability"].as_f64().unwrap() as f32, stopping["rule"]["agreeing"].as_u64().unwrap())
    );
    let eval = ok(&["eval", out.join("seed0/fold1").to_str().unwrap(), "--anytime"]);
    assert!(eval.contains("the validation answers of the cross-validation's 4 runs, 48 samples"), "{eval}");
    // The cross-validation as a whole: its runs' test accuracies as cv.json has them, and the
    // rule's change and share run by run as each run's own `eval --anytime` finds them.
    let whole = ok(&["eval", o]);
    let (mean, std) = (summary["mean_test_accuracy"].as_f64().unwrap(), summary["std_test_accuracy"].as_f64().unwrap());
    assert!(whole.contains(&format!("4 runs of {o}, fold 4: accuracy {mean:.4} ± {std:.4}")), "{whole}");
    assert!(whole.contains("their 48 answers together") && out.join("confusion-fold4.svg").exists(), "{whole}");
    let mean_std = |v: &[f64]| {
        let m = v.iter().sum::<f64>() / v.len() as f64;
        (m, (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt())
    };
    let (mut changes, mut shares) = (Vec::new(), Vec::new());
    for fold in 0..4 {
        let run = out.join(format!("seed0/fold{fold}"));
        let report: serde_json::Value = serde_json::from_str(&ok(&["eval", run.to_str().unwrap(), "--anytime", "--json"])).unwrap();
        let here = &report["stopping"];
        changes.push(100.0 * (here["accuracy"].as_f64().unwrap() - here["full_accuracy"].as_f64().unwrap()));
        shares.push(100.0 * here["mean_share"].as_f64().unwrap());
    }
    let ((change, change_std), (share, share_std)) = (mean_std(&changes), mean_std(&shares));
    let whole = ok(&["eval", o, "--anytime"]);
    let expected =
        format!("here, run by run: {change:+.1} ± {change_std:.1} points against the whole touch, at {share:.0} ± {share_std:.0} %");
    assert!(whole.contains(&expected) && out.join("anytime-fold4.svg").exists(), "{expected}\n{whole}");
    let err = fails(&["eval", o, "--pruned"]);
    assert!(err.contains("holds no finished run to evaluate (seed*/fold*/pruned/result.json)"), "{err}");
    std::fs::create_dir_all(out.join("seed3/fold1")).unwrap(); // a job still training
    let with_one_training = ok(&["eval", o]);
    assert!(with_one_training.contains(&format!("not finished, not counted: {o}/seed3/fold1")), "{with_one_training}");
    assert!(with_one_training.contains(&format!("4 runs of {o}, fold 4: accuracy {mean:.4}")), "{with_one_training}");
    std::fs::remove_dir_all(out.join("seed3")).unwrap();
    let weights = std::fs::read(out.join("seed0/fold3/model/weights.safetensors")).unwrap();
    args.push("--resume");
    let second = ok(&args);
    // The same summary and rule, all but the wall time.
    let tail =
        |s: &str| s.lines().filter(|l| !l.starts_with("next:")).map(|l| l.split(" (wall").next().unwrap()).collect::<Vec<_>>().join("\n");
    assert_eq!(tail(&first), tail(&second));
    assert_eq!(weights, std::fs::read(out.join("seed0/fold3/model/weights.safetensors")).unwrap(), "not retrained");

    // One run of another seed as its own job into the same directory, then a report of all.
    let mut one = vec!["cv", "--data", d, "--out", o, "--epochs", "1", "--only", "seed=1,fold=2"];
    one.extend(SMALL);
    let joined = ok(&one);
    assert!(joined.contains("over 5 runs"), "{joined}");
    std::fs::create_dir_all(out.join("seed1/fold0")).unwrap(); // a job still training
    let report = ok(&["cv", "--report", o]);
    assert!(
        report.contains("over 5 runs") && report.contains("not finished, not counted") && report.contains("95 % confidence"),
        "{report}"
    );
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("cv.json")).unwrap()).unwrap();
    assert_eq!(summary["seeds"], serde_json::json!([0, 1]));
    assert_eq!(summary["runs"].as_array().unwrap().len(), 5);
    assert_eq!(summary["stopping"]["calibrated_on"]["cross_validation"]["runs"], 5, "the report calibrates on every finished run");
    let err = fails(&["cv", "--data", d, "--out", o, "--only", "seed=1,fold=4"]);
    assert!(err.contains("expected seed=S,fold=K with a validation fold from 0 to 3"), "{err}");

    // Bad directories: nothing finished, runs trained differently, a damaged run. Nothing is deleted.
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let err = fails(&["cv", "--report", empty.to_str().unwrap()]);
    assert!(err.contains("no finished run under it"), "{err}");
    let mut other = vec!["cv", "--data", d, "--out", o, "--epochs", "1", "--lr", "0.01", "--only", "seed=2,fold=0"];
    other.extend(SMALL);
    let err = fails(&other);
    assert!(err.contains("were trained differently"), "{err}");
    std::fs::remove_dir_all(out.join("seed2")).unwrap();
    let result = out.join("seed0/fold1/result.json");
    std::fs::write(&result, "{ half").unwrap();
    let err = fails(&["cv", "--report", o]);
    assert!(err.contains("seed0/fold1 is damaged or half written"), "{err}");
    assert!(out.join("seed0/fold1/model/weights.safetensors").exists() && out.join("seed1/fold2/result.json").exists(), "nothing deleted");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn baselines_train_and_evaluate_but_do_not_export() {
    let dir = scratch("baselines");
    let data = icub_slice(&dir, 12);
    let d = data.to_str().unwrap();
    for model in ["vit", "raec"] {
        let run = dir.join(model);
        let r = run.to_str().unwrap();
        let mut args = vec!["train", "--data", d, "--out", r, "--epochs", "1", "--model", model];
        args.extend(SMALL);
        let out = ok(&args);
        assert!(out.contains("best epoch"), "{out}");
        let eval = ok(&["eval", r, "--data", d]);
        assert!(eval.contains("accuracy"), "{eval}");
        let info = ok(&["info", r]);
        assert!(info.contains(&format!("model         {model}")), "{info}");
        let err = fails(&["export", r, "-o", dir.join("x.onnx").to_str().unwrap()]);
        assert!(err.contains(&format!("PVT³ models only, and this is a {model} model")), "{err}");
    }
    let err = fails(&["train", "--data", d, "--out", dir.join("p").to_str().unwrap(), "--model", "raec", "--prune-channels", "50"]);
    assert!(err.contains("pruning and export: PVT³ models only"), "{err}");
    assert!(!dir.join("p").exists(), "refused before training");
    std::fs::remove_dir_all(dir).unwrap();
}

/// A sensor no preset fits (24 electrodes, 250 frames, 7 classes, like a public BioTac SP slip
/// set): `train` derives the BioTac layout and says so, and `eval` reads the run's own data.
#[test]
fn a_new_sensor_shape_trains_with_a_derived_layout() {
    let dir = scratch("sensor");
    let (n, frames) = (70, 250);
    let labels: Vec<i64> = (0..n).map(|i| i as i64 % 7).collect();
    let x: Vec<f32> = (0..n * 24 * frames).map(|i| ((i / (24 * frames)) % 7) as f32 + ((i * 7919) % 13) as f32 / 13.0).collect();
    let path = dir.join("slip.npz");
    let mut w = NpzWriter::new_compressed(std::fs::File::create(&path).unwrap());
    w.add_array("x", &ArrayD::from_shape_vec(IxDyn(&[n, 24, 1, frames]), x).unwrap()).unwrap();
    w.add_array("y", &Array1::from_vec(labels)).unwrap();
    w.finish().unwrap();
    let run = dir.join("run");
    let (d, r) = (path.to_str().unwrap(), run.to_str().unwrap());
    let out = pvt3(&["train", "--data", d, "--out", r, "--epochs", "1", "--set", "space_depth=1", "--set", "time_depth=1"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("no preset takes samples of 24 × 1 × 250: derived the BioTac layout, one token per 5 frames"), "{stderr}");
    let eval = ok(&["eval", r, "--fold", "all"]);
    assert!(eval.contains("70 samples (fold all)") && !eval.contains("Some("), "{eval}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn bad_input_gets_a_clear_error() {
    let dir = scratch("errors");
    let missing = dir.join("absent.npz");
    let err = fails(&["train", "--data", missing.to_str().unwrap(), "--out", dir.join("r").to_str().unwrap()]);
    assert!(err.contains("absent.npz") && err.contains("no such file or directory"), "{err}");
    // Outside a checkout, the default data set is not there: said so, with what to do.
    let out = Command::new(env!("CARGO_BIN_EXE_pvt3")).args(["train", "--out", "r"]).current_dir(&dir).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("the default data set ships in a checkout of pvt3") && err.contains("--data FILE"),
        "{err}"
    );
    let err = fails(&["train", "--preset", "biotac20", "--out", dir.join("r").to_str().unwrap()]);
    assert!(err.contains("samples are [6, 10, 75] but the model expects [19, 1, 400]"), "{err}");
    let err = fails(&["train", "--set", "depth=3", "--out", dir.join("r").to_str().unwrap()]);
    assert!(err.contains("unknown field `depth`"), "{err}");
    let err = fails(&["train", "--set", "patch_width=3", "--out", dir.join("r").to_str().unwrap()]);
    assert!(err.contains("patch_width = 3 does not divide width = 10"), "{err}");
    let err = fails(&["train", "--lr-floor", "2", "--out", dir.join("r").to_str().unwrap()]);
    assert!(err.contains("--lr-floor 2: expected a number in [0, 1]"), "{err}");
    for (option, value, range) in [("--lr", "NaN", "(0, 10]"), ("--aug-reverse", "2", "[0, 1]"), ("--ema", "1", "[0, 1)")] {
        let err = fails(&["train", option, value, "--out", dir.join("r").to_str().unwrap()]);
        assert!(err.contains(&format!("{option} {value}: expected a number in {range}")), "{err}");
    }
    let err = fails(&["train", "--batch-size", "0", "--out", dir.join("r").to_str().unwrap()]);
    assert!(err.contains("--batch-size 0: expected 1 to 1000000"), "{err}");
    let err = fails(&["eval", dir.to_str().unwrap()]);
    assert!(err.contains("not a checkpoint directory"), "{err}");
    assert!(!dir.join("r").exists(), "nothing written on failure");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn train_prune_fine_tune_and_bake_make_a_smaller_model() {
    let dir = scratch("prune");
    let data = icub_slice(&dir, 12);
    let run = dir.join("run");
    let (d, r) = (data.to_str().unwrap(), run.to_str().unwrap());
    let from_run = dir.join("run.onnx");
    let mut args = vec!["train", "--data", d, "--out", r, "--epochs", "1", "--l1", "0.01", "--random-prune", "0.1"];
    args.extend(["--prune-channels", "50", "--prune-frames", "40", "--fine-tune-epochs", "1"]);
    args.extend(["--export", from_run.to_str().unwrap()]);
    args.extend(SMALL);
    let out = ok(&args);
    assert!(out.contains("pruned and fine-tuned"), "{out}");
    let provenance: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("pruned/model/provenance.json")).unwrap()).unwrap();
    assert_eq!(provenance["pruning"]["channels"], 50.0);

    let info = ok(&["info", &format!("{r}/pruned")]);
    assert!(info.contains("after baking") && info.contains("45 of 75 temporal tokens kept"), "{info}");
    let baked = dir.join("baked.json");
    let out = ok(&["bake", &format!("{r}/pruned"), "-o", baked.to_str().unwrap()]);
    assert!(out.contains("45 of 75 temporal tokens kept"), "{out}");
    let file: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&baked).unwrap()).unwrap();
    assert_eq!(file["baked"]["kept_tokens"].as_array().unwrap().len(), 45);
    assert_eq!(file["baked"]["space"]["layers"][0]["attn"]["head_dim"], 32);
    assert_eq!(file["baked"]["space"]["layers"][0]["ffn"]["fc1"]["rows"], 20);

    let err = fails(&["prune", r, "--out", dir.join("p2").to_str().unwrap()]);
    assert!(err.contains("give --prune-channels, --prune-frames and/or --prune-weights"), "{err}");

    // Exported by `train --export` and from the baked file: onnxruntime on raw frames equals
    // candle on normalised ones.
    let from_baked = dir.join("baked.onnx");
    ok(&["export", baked.to_str().unwrap(), "-o", from_baked.to_str().unwrap()]);
    let (meta, model, _) = pvt3_trainer::checkpoint::load(&run.join("pruned")).unwrap();
    let d = Dataset::load(&data, 0).unwrap();
    let test: Vec<usize> = (0..d.len()).filter(|&i| d.folds[i] == 4).take(8).collect();
    let samples = pvt3_trainer::data::windows::Samples::new(&d, &test, &meta.normalization);
    let (x, _) = samples.batch(&(0..8).collect::<Vec<_>>(), |_| {}).unwrap();
    let expected = model.forward(&x, None).unwrap().flatten_all().unwrap().to_vec1::<f32>().unwrap();
    let raw: Vec<f32> = test.iter().flat_map(|&i| d.sample(i).to_vec()).collect();
    for onnx in [&from_run, &from_baked] {
        onnx_check::assert_onnxruntime_matches(onnx, (&[8, 6, 10, 75], &raw), &expected, 1e-5, None);
    }
    onnx_check::assert_onnxruntime_matches(&from_run, (&[1, 6, 10, 75], &raw[..4500]), &expected[..20], 1e-5, None);
    // The robot runtime (tract) agrees too.
    let (logits, _) = pvt3_runtime::Classifier::load(&from_run).unwrap().run(&raw, 8).unwrap();
    let worst = logits.iter().zip(&expected).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
    assert!(worst <= 1e-5, "tract against candle: {worst:e}");
    let err = fails(&["export", data.to_str().unwrap(), "-o", dir.join("x.onnx").to_str().unwrap()]);
    assert!(err.contains("neither a checkpoint directory nor a baked model"), "{err}");
    std::fs::remove_dir_all(dir).unwrap();
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            copy_dir(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), target).unwrap();
        }
    }
}

/// A run directory written by pvt3 before the model crate was split and the run directory typed
/// (commit 9809af1: a tiny model paused after one of three epochs,
/// `tests/fixtures/run-9809af1-paused`) still evaluates, resumes and exports; resumed, it ends
/// with the very weights an uninterrupted run of today's pvt3 gives.
#[test]
fn a_run_written_before_the_house_change_resumes_bit_for_bit() {
    let fixture = workspace::workspace().join("tests/fixtures/run-9809af1-paused");
    let dir = scratch("old-run");
    let (old, fresh) = (dir.join("old"), dir.join("fresh"));
    copy_dir(&fixture, &old);
    let (old_s, fresh_s) = (old.to_str().unwrap(), fresh.to_str().unwrap());
    let eval = ok(&["eval", old_s]);
    assert!(eval.contains("samples (fold 4): accuracy"), "{eval}");
    let tiny =
        ["--epochs", "3", "--set", "dim=8", "--set", "dim_head=8", "--set", "mlp_dim=8", "--set", "space_depth=1", "--set", "time_depth=1"];
    ok(&[&["train", "--resume", "--out", old_s][..], &tiny].concat());
    ok(&[&["train", "--out", fresh_s][..], &tiny].concat());
    for file in ["model/weights.safetensors", "last/weights.safetensors", "last/optimizer.safetensors"] {
        assert!(std::fs::read(old.join(file)).unwrap() == std::fs::read(fresh.join(file)).unwrap(), "{file} differs");
    }
    assert_eq!(std::fs::read_to_string(old.join("metrics.jsonl")).unwrap().lines().count(), 3);
    let onnx = dir.join("old.onnx");
    ok(&["export", old_s, "-o", onnx.to_str().unwrap()]);
    assert!(pvt3_runtime::Classifier::load(&onnx).is_ok());
    std::fs::remove_dir_all(dir).unwrap();
}

/// A folder of CSV touches of unequal length (three classes, an extra time-stamp column and a
/// constant one) to an exported model in three commands, leaving its pictures on the way.
#[test]
fn csv_touches_of_any_length_import_cross_validate_and_export() {
    let dir = scratch("csv");
    let csvs = dir.join("csvs");
    csv_tree::write(&csvs, 3, 10, 40, 64);
    let (data, out, onnx) = (dir.join("set.npz"), dir.join("cv"), dir.join("model.onnx"));
    let (d, o) = (data.to_str().unwrap(), out.to_str().unwrap());
    let imported = ok(&["import", csvs.to_str().unwrap(), "--out", d]);
    assert!(imported.contains("30 touches of 3 classes") && imported.contains("left out: time (a time stamp by its name)"), "{imported}");
    let mut args = vec!["cv", "--data", d, "--out", o, "--epochs", "12", "--jobs", "2", "--set", "frames=32", "--set", "tubelet=4"];
    args.extend(SMALL);
    let cv = pvt3(&args);
    let stderr = String::from_utf8_lossy(&cv.stderr);
    assert!(cv.status.success(), "{stderr}");
    assert!(stderr.contains("touches of 4") && stderr.contains("reads windows of"), "{stderr}");
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("cv.json")).unwrap()).unwrap();
    let accuracy = summary["mean_test_accuracy"].as_f64().unwrap();
    assert!(accuracy >= 0.8, "the classes differ in level and frequency, and are learnt: {accuracy}");
    for fold in 0..4 {
        assert!(out.join(format!("seed0/fold{fold}/curves.svg")).exists(), "fold {fold}");
    }
    assert!(out.join("cv-curves.svg").exists());
    the_final_model_trains_on_every_touch_as_the_cv_chose(&out, &summary, 30);
    // A cross-validation taught by this one has no final model, and says what to ship instead.
    let taught = dir.join("taught");
    let mut args = vec!["cv", "--data", d, "--out", taught.to_str().unwrap(), "--distill", o, "--epochs", "2", "--jobs", "2"];
    args.extend(["--set", "frames=32", "--set", "tubelet=4"].into_iter().chain(SMALL));
    ok(&args);
    let refused = fails(&["final", taught.to_str().unwrap()]);
    let instead = format!("pvt3 export {}", taught.join("seed0/fold0").display());
    assert!(refused.contains(&instead) && refused.contains(&format!("pvt3 final {o}")), "{refused}");
    a_final_model_is_tested_on_new_touches_alone(&dir, &csvs, &out.join("final"));
    let run = out.join("seed0/fold0");
    let eval = ok(&["eval", run.to_str().unwrap()]);
    assert!(eval.contains("material_2") && eval.contains("confusion matrix") && run.join("confusion-fold4.svg").exists(), "{eval}");
    std::fs::remove_file(run.join("curves.svg")).unwrap();
    ok(&["plot", o]);
    assert!(run.join("curves.svg").exists(), "plot draws again");
    ok(&["export", run.to_str().unwrap(), "-o", onnx.to_str().unwrap()]);
    let c = pvt3_runtime::Classifier::load(&onnx).unwrap();
    assert_eq!(c.sample_shape(), &[4, 1, 32]);
    assert_eq!(c.classes(), &["material_0", "material_1", "material_2"]);
    // A whole touch from its CSV file, streamed: a session over its first window equals the
    // window classified, and a continuous stream over all of it answers for each latest window.
    let text = std::fs::read_to_string(csvs.join("material_2/touch_03.csv")).unwrap();
    let frames: Vec<Vec<f32>> = text.lines().skip(1).map(|l| l.split(',').skip(1).take(4).map(|v| v.parse().unwrap()).collect()).collect();
    let window = |end: usize| -> Vec<f32> { (0..4).flat_map(|e| frames[end - 32..end].iter().map(move |f| f[e])).collect() };
    let mut session = c.session().unwrap();
    frames[..32].iter().for_each(|f| session.push_frame(f).unwrap());
    let (streamed, whole) = (session.finish().unwrap(), c.classify(&window(32)).unwrap());
    assert!(streamed.probabilities.iter().zip(&whole.probabilities).all(|(a, b)| (a - b).abs() <= 1e-5));
    let mut slide = c.continuous(1).unwrap();
    let mut answers = 0;
    for (t, f) in frames.iter().enumerate() {
        if let Some(p) = slide.push_frame(f).unwrap() {
            assert_eq!(p, c.classify(&window(t + 1)).unwrap(), "the window ending at frame {}", t + 1);
            answers += 1;
        }
    }
    assert_eq!(answers, (frames.len() - 32) / 4 + 1, "after every token of 4 frames once a window is in");
    std::fs::remove_dir_all(dir).unwrap();
}

/// `pvt3 final` on the cross-validation in `cv` (summarised by `summary`) over a set of `touches`:
/// trained on all of them for the median of the epochs its runs selected, with the stopping rule
/// the cross-validation wrote into its runs; the file states the cross-validation's accuracy, and
/// `pvt3 eval` refuses to test it on the touches that trained it.
fn the_final_model_trains_on_every_touch_as_the_cv_chose(cv: &Path, summary: &serde_json::Value, touches: u64) {
    let onnx = cv.join("final.onnx");
    let printed = ok(&["final", cv.to_str().unwrap(), "-o", onnx.to_str().unwrap(), "--json"]);
    let done: serde_json::Value = serde_json::from_str(&printed).unwrap();
    let mut selected: Vec<u64> = summary["runs"].as_array().unwrap().iter().map(|r| r["best_epoch"].as_u64().unwrap()).collect();
    selected.sort_unstable();
    let median = selected[selected.len() / 2];
    assert_eq!((done["touches"].as_u64(), done["epochs"].as_u64()), (Some(touches), Some(median)), "{printed}");
    for key in ["mean_test_accuracy", "std_test_accuracy", "ci95_test_accuracy"] {
        assert_eq!(done["expected"][key], summary[key], "{key}");
    }
    // Where there is no interval (one seed), the file says why.
    let why = done["expected"]["no_interval"].as_str().unwrap_or_default();
    assert_eq!(why.contains("needs two seeds at least"), summary["ci95_test_accuracy"].is_null(), "{printed}");
    let provenance = |run: &Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(run.join("model/provenance.json")).unwrap()).unwrap()
    };
    let (last, fold0) = (provenance(&cv.join("final")), provenance(&cv.join("seed0/fold0")));
    assert!(last["val_fold"].is_null() && last["trained_on"]["digest"] == fold0["trained_on"]["digest"], "{last}");
    assert_eq!(last["epoch"].as_u64(), Some(median));
    assert!(last["stopping"].is_object() && last["stopping"] == fold0["stopping"], "the cross-validation's rule");
    let file = String::from_utf8_lossy(&std::fs::read(&onnx).unwrap()).to_string();
    assert!(file.contains(&format!("\"selected_epochs\":{}", done["expected"]["selected_epochs"])), "the file states what it expects");
    let refused = fails(&["eval", cv.join("final").to_str().unwrap()]);
    assert!(
        refused.contains("none is left to test it") && refused.contains(&format!("{:.4}", summary["mean_test_accuracy"].as_f64().unwrap())),
        "{refused}"
    );
}

/// A final model (`last`, trained on the touches of `csvs`) evaluated on other data: its own
/// touches imported again without one class, or in another file, are refused with their count;
/// touches it never read are tested.
fn a_final_model_is_tested_on_new_touches_alone(dir: &Path, csvs: &Path, last: &Path) {
    let (subset, other) = (dir.join("subset"), dir.join("other"));
    std::fs::create_dir_all(&subset).unwrap();
    for class in ["material_0", "material_1"] {
        copy_dir(&csvs.join(class), &subset.join(class));
    }
    let (s, o) = (dir.join("subset.npz"), dir.join("other.npz"));
    ok(&["import", subset.to_str().unwrap(), "--out", s.to_str().unwrap()]);
    let refused = fails(&["eval", last.to_str().unwrap(), "--data", s.to_str().unwrap(), "--fold", "all"]);
    assert!(refused.contains("20 of the 20 touches to test") && refused.contains("trained it"), "{refused}");
    // Touches of other lengths, so other values: none trained the model.
    csv_tree::write(&other, 3, 10, 41, 60);
    ok(&["import", other.to_str().unwrap(), "--out", o.to_str().unwrap()]);
    let tested = ok(&["eval", last.to_str().unwrap(), "--data", o.to_str().unwrap(), "--fold", "all"]);
    assert!(tested.contains("30 samples (fold all"), "{tested}");
}

/// A scratch folder holding `flat/`: CSV touches of 3 classes, `touches` each, side by side and
/// named as FabricSlide names its files (`csv_tree::flatten`).
fn fabric_like(tag: &str, touches: usize) -> (PathBuf, PathBuf) {
    let dir = scratch(tag);
    let (tree, flat) = (dir.join("tree"), dir.join("flat"));
    csv_tree::write(&tree, 3, touches, 40, 64);
    csv_tree::flatten(&tree, &flat, 3, touches);
    (dir, flat)
}

/// A camera's touches as a user brings them, MPEG-4 videos named `<object>_<n>.mov` side by side
/// (as PhysiCLeAR's, made here by FFmpeg's test sources): imported shrunk, grey and minus each
/// touch's first frame, then trained on and exported, the file saying how a camera's frames are
/// read; options of the other kind of touch refused.
#[test]
fn a_camera_s_videos_import_and_train() {
    let dir = scratch("camera");
    let videos = dir.join("videos");
    std::fs::create_dir_all(&videos).unwrap();
    for (object, source) in [("striped_cloth", "testsrc"), ("smooth_tile", "testsrc2")] {
        for n in 0..5 {
            let input = format!("{source}=size=64x48:rate=25:duration=1.6,hue=h={}", 20 * n);
            let file = videos.join(format!("{object}_{n}.mov"));
            let made = Command::new("ffmpeg").args(["-v", "error", "-f", "lavfi", "-i", &input, "-c:v", "mpeg4"]).arg(&file).output();
            let made = made.expect("ffmpeg runs (apt-get install ffmpeg)");
            assert!(made.status.success(), "{}", String::from_utf8_lossy(&made.stderr));
        }
    }
    let (data, run) = (dir.join("set.npz"), dir.join("run"));
    let (v, d, r) = (videos.to_str().unwrap(), data.to_str().unwrap(), run.to_str().unwrap());
    let args = ["import", v, "--name", "{class}_*", "--size", "12x16", "--grey", "--frames", "8", "--subtract-first", "--out", d];
    let imported = ok(&args);
    assert!(
        imported.contains("10 touches of 2 classes (5 to 5 touches a class): 8 frames of 12 × 16 grey each, stored as 8-bit"),
        "{imported}"
    );
    assert!(imported.contains("first frame kept as its background"), "{imported}");
    let set = Dataset::load(&data, 0).unwrap();
    assert_eq!(
        (set.sample_shape.clone(), set.class_names.clone().unwrap()),
        (vec![12, 16, 8], vec!["smooth_tile".to_string(), "striped_cloth".to_string()])
    );
    assert!(
        (0..set.len()).any(|i| set.sample(i).iter().any(|v| *v < 0.0)),
        "frames minus the first: some pixels darker than before contact"
    );
    let onnx = dir.join("model.onnx");
    let mut args = vec!["train", "--data", d, "--out", r, "--epochs", "1", "--export", onnx.to_str().unwrap()];
    args.extend(SMALL);
    succeeds(&args);
    // The exported file says how the camera's frames were read; a session takes them as FFmpeg
    // gives them, 48 × 64 RGB, the first of a touch its background.
    let c = pvt3_runtime::Classifier::load(&onnx).unwrap();
    let camera = pvt3_runtime::Camera { recorded: [48, 64, 3], crop: None, size: Some([12, 16]), grey: true, subtract_first: true };
    assert_eq!(c.camera(), Some(camera));
    let raw = Command::new("ffmpeg")
        .args(["-v", "error", "-i"])
        .arg(videos.join("smooth_tile_0.mov"))
        .args(["-f", "rawvideo", "-pix_fmt", "rgb24", "-"])
        .output()
        .unwrap();
    let mut session = c.session().unwrap();
    raw.stdout.chunks(48 * 64 * 3).take(9).for_each(|frame| session.push_camera_frame(frame).unwrap());
    assert_eq!(session.finish().unwrap().probabilities.len(), 2);
    let err = fails(&["import", v, "--grid", "3x4", "--out", d]);
    assert!(err.contains("--grid is for CSV touches") && err.contains("holds a camera's (videos or frame folders)"), "{err}");
    let csvs = dir.join("csvs");
    csv_tree::write(&csvs, 3, 6, 40, 64);
    let err = fails(&["import", csvs.to_str().unwrap(), "--crop", "8x8+0+0", "--out", d]);
    assert!(err.contains("--crop is for a camera's touches (videos or frame folders)"), "{err}");
    std::fs::remove_dir_all(dir).unwrap();
}

/// Touches whose file names say their class, force and speed (as FabricSlide names them): imported
/// with their conditions, cross-validated with one force held out as the test set (augmented in
/// speed and pressure as asked), and evaluated on exactly the held-out touches again from the run
/// alone; one class's touches at that force held out alone; by default (`--robust auto`) the
/// touches' forces also scale each channel and stretch the windows in training, and the model
/// reads the channels' spectra.
#[test]
fn conditions_from_file_names_hold_out_a_force() {
    let (dir, flat) = fabric_like("hold-out", 12);
    let (data, out) = (dir.join("set.npz"), dir.join("cv"));
    let (d, o) = (data.to_str().unwrap(), out.to_str().unwrap());
    let imported = ok(&["import", flat.to_str().unwrap(), "--name", "{class}_F{force}_V{speed}mmps_*", "--out", d]);
    assert!(imported.contains("36 touches of 3 classes") && imported.contains("condition force: 120, 150, 210"), "{imported}");
    let mut args = vec!["cv", "--data", d, "--out", o, "--epochs", "12", "--jobs", "2", "--set", "frames=32", "--set", "tubelet=4"];
    args.extend(["--hold-out", "force=210", "--aug-stretch", "0.2", "--aug-scale", "0.05"]);
    args.extend(SMALL);
    let cv = pvt3(&[&args[..], &["--robust", "off"]].concat());
    let (stdout, stderr) = (String::from_utf8_lossy(&cv.stdout), String::from_utf8_lossy(&cv.stderr));
    assert!(cv.status.success(), "{stderr}");
    assert!(stderr.contains("held out force=210: 12 touches test, the other 24 train and validate"), "{stderr}");
    assert!(stdout.contains("the test set of every run: the touches of force=210"), "{stdout}");
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("cv.json")).unwrap()).unwrap();
    assert_eq!(summary["held_out"]["levels"], serde_json::json!(["210"]));
    let accuracy = summary["mean_test_accuracy"].as_f64().unwrap();
    assert!(accuracy >= 0.8, "the classes differ in level and frequency at every force: {accuracy}");
    // The run remembers what it held out: its test fold is the 12 touches pressed at 210.
    let eval = ok(&["eval", out.join("seed0/fold1").to_str().unwrap()]);
    assert!(eval.contains("12 samples (fold 4"), "{eval}");
    // Its accuracy at each level of the touches' conditions: all 12 at force 210, the runs'
    // answers pooled over the cross-validation.
    let level = |eval: &str, level: &str| {
        eval.lines().find(|l| l.starts_with(&format!("{level} "))).map(|l| l.split_whitespace().nth(1).unwrap().to_string())
    };
    assert_eq!(level(&eval, "210").as_deref(), Some("12"), "{eval}");
    assert_eq!(level(&ok(&["eval", o]), "210").as_deref(), Some("48"), "4 runs × 12 touches");
    // One class's touches at 210 held out, the others trained at 210 too; by default the touches
    // that train, pressed in three ways, say the robot will press in others.
    let auto = dir.join("auto");
    (args[4], args[6]) = (auto.to_str().unwrap(), "1");
    args.extend(["--only", "seed=0,fold=1", "--hold-out-class", "Fabric1"]);
    let cv = pvt3(&args);
    let stderr = String::from_utf8_lossy(&cv.stderr);
    assert!(cv.status.success() && stderr.contains("(condition force in 3 levels), so a robot will touch in others"), "{stderr}");
    assert!(stderr.contains("held out force=210 of class Fabric1: 4 touches test, the other 32 train"), "{stderr}");
    let eval = ok(&["eval", auto.join("seed0/fold1").to_str().unwrap()]);
    assert!(eval.contains("4 samples (fold 4"), "{eval}");
    let provenance = std::fs::read_to_string(auto.join("seed0/fold1/model/provenance.json")).unwrap();
    let options = &serde_json::from_str::<serde_json::Value>(&provenance).unwrap()["options"];
    let robust = (&options["robust"], &options["aug_channel_scale"], &options["aug_stretch"], &options["extrapolate"]);
    let trained = (&"auto".into(), &0.15.into(), &0.2.into(), &0.0.into());
    assert_eq!(robust, trained, "the run records what it trained with, the stretch asked kept");
    let config = std::fs::read_to_string(auto.join("seed0/fold1/model/config.json")).unwrap();
    let bands = &serde_json::from_str::<serde_json::Value>(&config).unwrap()["spectral_bands"];
    assert_eq!(bands, 16, "a window of 32 frames holds the spectral head's 16 bands");
    std::fs::remove_dir_all(dir).unwrap();
}

/// What a robot knows, used: touches imported by distance travelled and scaled to one force
/// (`--per-distance`, `--per-force`); the exported file says so, and the runtime brings a touch
/// straight from its CSV file, with its speed and force, to the very frames the training read.
#[test]
fn a_robot_reads_a_touch_by_its_speed_and_force_as_the_import_did() {
    let (dir, flat) = fabric_like("reading", 6);
    let (data, run, onnx) = (dir.join("set.npz"), dir.join("run"), dir.join("model.onnx"));
    let d = data.to_str().unwrap();
    let mut args = vec!["import", flat.to_str().unwrap(), "--name", "{class}_F{force}_V{speed}mmps_*", "--out", d];
    args.extend(["--per-distance", "speed=10", "--per-force", "force=150"]);
    let imported = ok(&args);
    assert!(imported.contains("resampled from time to distance") && imported.contains("scaled to force 150"), "{imported}");
    let mut args = vec!["train", "--data", d, "--out", run.to_str().unwrap(), "--epochs", "2", "--set", "frames=32", "--set", "tubelet=4"];
    args.extend(SMALL);
    args.extend(["--export", onnx.to_str().unwrap()]);
    ok(&args);
    let c = pvt3_runtime::Classifier::load(&onnx).unwrap();
    assert_eq!(c.reading(), Some(pvt3_runtime::Reading { speed: Some(10.0), force: Some(150.0) }));
    // A touch at 50 mm/s pressed at 210, from its file: five times the frames, 150/210 of each value.
    let name = "Fabric1_F210_V50mmps_5.csv";
    let text = std::fs::read_to_string(flat.join(name)).unwrap();
    let rows: Vec<Vec<f32>> = text.lines().skip(1).map(|l| l.split(',').skip(1).take(4).map(|v| v.parse().unwrap()).collect()).collect();
    let frames: Vec<f32> = (0..4).flat_map(|e| rows.iter().map(move |r| r[e])).collect();
    let read = c.read_touch(&frames, pvt3_runtime::Touch { speed: Some(50.0), force: Some(210.0) }).unwrap();
    assert_eq!(read.len(), 4 * rows.len() * 5);
    let set = Dataset::load(&data, 0).unwrap();
    let i = set.sources.as_ref().unwrap().iter().position(|s| s == name).unwrap();
    let n = set.lengths[i];
    let imported: Vec<f32> = set.sample(i).chunks(set.max_frames()).flat_map(|row| row[..n].to_vec()).collect();
    assert_eq!(read, imported, "the robot reads the touch as the training's import did, bit for bit");
    let window: Vec<f32> = read.chunks(n).flat_map(|row| row[..32].to_vec()).collect();
    assert!(c.classify(&window).is_ok());
    // Streamed as recorded: a session for the touch takes the file's rows one at a time and
    // answers, provisionally and at the end, as a session given the window read_touch returns.
    let touch = pvt3_runtime::Touch { speed: Some(50.0), force: Some(210.0) };
    let (mut recorded, mut given) = (c.session_for(touch).unwrap(), c.session().unwrap());
    let frame_of = |frames: &[f32], len: usize, t: usize| -> Vec<f32> { (0..4).map(|e| frames[e * len + t]).collect() };
    let (mut pushed, mut peeks) = (0, 0);
    while recorded.received() < recorded.frames() {
        recorded.push_frame(&rows[pushed]).unwrap();
        pushed += 1;
        while given.received() < recorded.received() {
            given.push_frame(&frame_of(&window, 32, given.received())).unwrap();
        }
        if let (Ok(a), Ok(b)) = (recorded.peek(), given.peek()) {
            assert_eq!((a.prediction.probabilities, a.frames), (b.prediction.probabilities, b.frames));
            peeks += 1;
        }
    }
    assert!(pushed <= 32 / 5 + 2 && peeks >= 4, "{pushed} recorded frames for 32 read, {peeks} peeks");
    assert!(matches!(recorded.push_frame(&rows[pushed]), Err(pvt3_runtime::Error::TooManyFrames { .. })));
    let (a, b) = (recorded.finish().unwrap(), given.finish().unwrap());
    assert_eq!(a.probabilities, b.probabilities, "the same frames, the same answer, bit for bit");
    assert!(c.classify(&window).unwrap().probabilities.iter().zip(&a.probabilities).all(|(x, y)| (x - y).abs() < 1e-5));
    let err = c.read_touch(&frames, pvt3_runtime::Touch { speed: Some(50.0), force: None }).unwrap_err().to_string();
    assert!(err.contains("give the touch's force"), "{err}");
    std::fs::remove_dir_all(dir).unwrap();
}

/// `pvt3 cv --joint`: a network per sensor trained together, each reported on its own sensor,
/// each pruned and exported alone (the other sensor's runs in OUT/seed*/fold*/partner), and the
/// report of the directory gives both again.
#[test]
fn joint_cv_trains_a_network_per_sensor_and_each_is_pruned_and_exported_alone() {
    let dir = scratch("joint");
    // BioTac's touches are in class order within a fold: every tenth is one of each class.
    let (icub, biotac) = (icub_slice(&dir, 12), slice("biotac20", &dir, 20, 10));
    let out = dir.join("cv");
    let (d, b, o) = (icub.to_str().unwrap(), biotac.to_str().unwrap(), out.to_str().unwrap());
    let mut args = vec!["cv", "--data", d, "--joint", b, "--joint-after", "1", "--out", o, "--epochs", "2", "--only", "seed=0,fold=1"];
    args.extend(["--prune-channels", "0.5", "--fine-tune-epochs", "1"]);
    args.extend(SMALL);
    let printed = ok(&args);
    assert!(printed.contains(&format!("the other sensor's networks, trained beside on {b}")), "{printed}");
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("cv.json")).unwrap()).unwrap();
    let partner = &summary["partner"];
    assert_eq!((partner["data"].as_str(), partner["runs"].as_array().unwrap().len()), (Some(b), 1), "{summary}");
    assert_eq!(partner["pruned_runs"].as_array().unwrap().len(), 1, "{summary}");
    assert!(out.join("cv-partner-curves.svg").exists());
    let run = out.join("seed0/fold1");
    let provenance: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("partner/model/provenance.json")).unwrap()).unwrap();
    assert_eq!(provenance["options"]["joint"]["partner"].as_str(), Some(d));
    let pruned: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("partner/pruned/model/provenance.json")).unwrap()).unwrap();
    assert!(pruned["options"].get("joint").is_none(), "fine-tuned alone: {pruned}");
    // Each sensor's pruned model is its own file, reading its own sensor's touches.
    for (net, shape) in [("pruned", vec![6, 10, 75]), ("partner/pruned", vec![19, 1, 400])] {
        let onnx = dir.join(format!("{}.onnx", net.replace('/', "-")));
        ok(&["export", run.join(net).to_str().unwrap(), "-o", onnx.to_str().unwrap()]);
        assert_eq!(pvt3_runtime::Classifier::load(&onnx).unwrap().sample_shape(), shape.as_slice(), "{net}");
    }
    let weights = std::fs::read(run.join("partner/model/weights.safetensors")).unwrap();
    args.push("--resume");
    ok(&args);
    assert_eq!(weights, std::fs::read(run.join("partner/model/weights.safetensors")).unwrap(), "not retrained");
    let report = ok(&["cv", "--report", o]);
    assert!(report.contains("the other sensor's networks") && report.contains("over 1 runs"), "{report}");
    let again: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("cv.json")).unwrap()).unwrap();
    assert_eq!(again["partner"]["runs"], partner["runs"]);
    std::fs::remove_dir_all(dir).unwrap();
}

/// docs/deploy.md's onnxruntime example (runtime/examples/onnxruntime_classify.py), run as a user
/// would on the golden model's windows: the classes and probabilities the runtime gives.
#[test]
fn the_onnxruntime_example_of_the_docs_classifies_as_the_runtime_does() {
    let golden = workspace::workspace().join("tests/golden/icub20");
    let (model, input) = (golden.join("model.onnx"), golden.join("input.npy"));
    let printed = onnx_check::run_script("runtime/examples/onnxruntime_classify.py", &[&model, &input]);
    let c = pvt3_runtime::Classifier::load(&model).unwrap();
    let (_, x) = pvt3_runtime::read_npy(&input).unwrap();
    let expected = c.classify_batch(&x, 8).unwrap();
    assert_eq!(printed.lines().count(), 8, "{printed}");
    for (line, p) in printed.lines().zip(&expected) {
        let fields: Vec<&str> = line.split('\t').collect();
        assert_eq!((fields[1].parse::<usize>().unwrap(), fields[2]), (p.class, p.label.as_str()), "{line}");
        assert!((fields[3].parse::<f32>().unwrap() - p.probabilities[p.class]).abs() < 1e-5, "{line}");
    }
}

/// `--json`: train, eval and cv print their result as one JSON object on standard output, the
/// same figures their files and tables hold, and nothing else there.
#[test]
fn train_eval_and_cv_print_their_result_as_json() {
    let dir = scratch("json");
    let data = icub_slice(&dir, 10);
    let (d, run, cv) = (data.to_str().unwrap(), dir.join("run"), dir.join("cv"));
    let mut args = vec!["train", "--data", d, "--out", run.to_str().unwrap(), "--epochs", "1", "--json"];
    args.extend(SMALL);
    let trained: serde_json::Value = serde_json::from_str(&ok(&args)).expect("one JSON object");
    let recorded: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(run.join("result.json")).unwrap()).unwrap();
    assert_eq!(trained["run"], recorded);
    assert_eq!(trained["checkpoint"], run.join("model").display().to_string());
    assert!(trained["pruned"].is_null() && trained["onnx"].is_null(), "{trained}");
    let eval: serde_json::Value = serde_json::from_str(&ok(&["eval", run.to_str().unwrap(), "--json"])).unwrap();
    assert_eq!(eval["accuracy"], recorded["test_accuracy"]);
    assert_eq!((eval["touches"].as_u64(), eval["fold"].as_str()), (Some(10), Some("4")));
    let confusion = eval["confusion"].as_array().unwrap();
    assert_eq!(confusion.len(), 20);
    let total: u64 = confusion.iter().flat_map(|row| row.as_array().unwrap()).map(|v| v.as_u64().unwrap()).sum();
    assert_eq!(total, 10, "every touch once in the confusion matrix");
    let mut args = vec!["cv", "--data", d, "--out", cv.to_str().unwrap(), "--epochs", "1", "--only", "seed=0,fold=1", "--json"];
    args.extend(SMALL);
    let summary: serde_json::Value = serde_json::from_str(&ok(&args)).unwrap();
    let written: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(cv.join("cv.json")).unwrap()).unwrap();
    assert_eq!(summary, written, "what cv.json holds");
    std::fs::remove_dir_all(dir).unwrap();
}
