//! The robot-side command on the committed golden model: one line per window, the class the
//! golden logits pick, and clear failures.

use std::path::{Path, PathBuf};
use std::process::Command;

use pvt3_runtime::read_npy;

fn golden(file: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/golden/icub20").join(file)
}

#[test]
fn classifies_every_window_of_an_npy_batch_as_the_golden_logits_do() {
    let (shape, logits) = read_npy(&golden("logits.npy")).unwrap();
    assert_eq!(shape, vec![8, 20]);
    let out = Command::new(env!("CARGO_BIN_EXE_pvt3-run")).arg(golden("model.onnx")).arg(golden("input.npy")).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let lines: Vec<String> = String::from_utf8(out.stdout).unwrap().lines().map(String::from).collect();
    assert_eq!(lines.len(), 8);
    for (i, (line, row)) in lines.iter().zip(logits.chunks(20)).enumerate() {
        let best = row.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).unwrap().0;
        assert!(line.starts_with(&format!("{i}\t{best}\tmaterial_{}\t", best + 1)), "{line}");
    }
}

#[test]
fn wrong_input_fails_with_a_message() {
    let out = Command::new(env!("CARGO_BIN_EXE_pvt3-run")).arg(golden("model.onnx")).arg(golden("logits.npy")).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("input has 160 values; expected"), "{err}");
    let out = Command::new(env!("CARGO_BIN_EXE_pvt3-run")).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let out = Command::new(env!("CARGO_BIN_EXE_pvt3-run")).arg(golden("manifest.json")).arg(golden("input.npy")).output().unwrap();
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("manifest.json"));
}
