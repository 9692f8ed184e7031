//! The robot-side command on the committed golden model: one line per window, the class the
//! golden logits pick, and clear failures.

mod support;

use std::process::Command;

use pvt3_runtime::read_npy;
use support::{golden, target_command};

fn pvt3_run() -> Command {
    target_command(env!("CARGO_BIN_EXE_pvt3-run"))
}

#[test]
fn classifies_every_window_of_an_npy_batch_as_the_golden_logits_do() {
    let (shape, logits) = read_npy(&golden("logits.npy")).unwrap();
    assert_eq!(shape, vec![8, 20]);
    let out = pvt3_run().arg(golden("model.onnx")).arg(golden("input.npy")).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let lines: Vec<String> = String::from_utf8(out.stdout).unwrap().lines().map(String::from).collect();
    assert_eq!(lines.len(), 8);
    for (i, (line, row)) in lines.iter().zip(logits.chunks(20)).enumerate() {
        let best = row.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).unwrap().0;
        assert!(line.starts_with(&format!("{i}\t{best}\tmaterial_{}\t", best + 1)), "{line}");
    }
}

/// `--json`: one object per window, with every probability, the same answers as the lines. Its
/// place on the command line is free (here last).
#[test]
fn json_gives_every_probability_of_every_window() {
    let (_, logits) = read_npy(&golden("logits.npy")).unwrap();
    let out = pvt3_run().arg(golden("model.onnx")).arg(golden("input.npy")).arg("--json").output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let lines: Vec<serde_json::Value> = String::from_utf8(out.stdout).unwrap().lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    assert_eq!(lines.len(), 8);
    for (i, (line, row)) in lines.iter().zip(logits.chunks(20)).enumerate() {
        let best = row.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).unwrap().0;
        assert_eq!((line["window"].as_u64(), line["class"].as_u64()), (Some(i as u64), Some(best as u64)));
        assert_eq!(line["label"], format!("material_{}", best + 1));
        let probabilities: Vec<f64> = line["probabilities"].as_array().unwrap().iter().map(|p| p.as_f64().unwrap()).collect();
        assert!(probabilities.len() == 20 && (probabilities.iter().sum::<f64>() - 1.0).abs() < 1e-5, "{line}");
    }
}

/// `--help` and `--version` answer on standard output and succeed.
#[test]
fn help_and_version_succeed() {
    for flag in ["--help", "-h"] {
        let out = pvt3_run().arg(flag).output().unwrap();
        assert!(out.status.success() && String::from_utf8_lossy(&out.stdout).starts_with("usage: pvt3-run"), "{flag}");
    }
    let out = pvt3_run().arg("--version").output().unwrap();
    let (major, minor) = pvt3_format::FORMAT_VERSION;
    let expected = format!("pvt3-run {} (format {major}.{minor})\n", env!("CARGO_PKG_VERSION"));
    assert!(out.status.success());
    assert_eq!(String::from_utf8_lossy(&out.stdout), expected);
}

#[test]
fn wrong_input_fails_with_a_message() {
    let out = pvt3_run().arg(golden("model.onnx")).arg(golden("logits.npy")).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(
            "logits.npy: an array of shape [8, 20]; the model reads one window of 6 × 10 × 75 (height × width × [channels ×] frames)"
        ),
        "{err}"
    );
    // A command line it cannot read: exit status 2, what is wrong, then the usage.
    for (args, why) in
        [(&[][..], "pvt3-run: expected MODEL.onnx INPUT.npy"), (&["a.onnx", "--jsn", "b.npy"][..], "pvt3-run: no option `--jsn`")]
    {
        let out = pvt3_run().args(args).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.code() == Some(2) && err.starts_with(why) && err.contains("usage: pvt3-run"), "{args:?}: {err}");
    }
    let out = pvt3_run().arg(golden("manifest.json")).arg(golden("input.npy")).output().unwrap();
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("manifest.json"));
}

#[test]
fn bench_reports_batch_and_streaming_latencies() {
    let out = pvt3_run().args(["--bench"]).arg(golden("model.onnx")).args(["1", "0.05"]).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!((report["frames"].as_u64(), report["kept_frames"].as_u64()), (Some(75), Some(55)));
    for key in [
        "batch1_median_us",
        "batch1_untuned_median_us",
        "batch1_measured_median_us",
        "load_ms",
        "digest_check_ms",
        "prepare_ms",
        "batch1_first_call_after_prepare_ms",
        "batch32_windows_per_second",
        "stream_kept_frame_median_us",
        "stream_end_of_touch_median_us",
    ] {
        assert!(report[key].as_f64().unwrap() > 0.0, "{key}: {report}");
    }
    assert!(report["batch1_p99_us"].as_f64() >= report["batch1_median_us"].as_f64());
    let out = pvt3_run().args(["--bench"]).arg(golden("model.onnx")).arg("zero").output().unwrap();
    assert_eq!(out.status.code(), Some(2), "a bad thread count gets the usage");
}
