//! Running the `pvt3` command from the end-to-end tests: from the workspace's root, as a user of a
//! checkout would, with its output checked.

use std::path::PathBuf;
use std::process::{Command, Output};

pub fn pvt3(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pvt3")).args(args).current_dir(super::workspace::workspace()).output().expect("pvt3 runs")
}

/// Runs `pvt3 args`, which must succeed: its whole output.
pub fn succeeds(args: &[&str]) -> Output {
    let out = pvt3(args);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "pvt3 {args:?} failed:\n{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
    out
}

/// Runs `pvt3 args`, which must succeed: what it printed on standard output.
pub fn ok(args: &[&str]) -> String {
    String::from_utf8_lossy(&succeeds(args).stdout).to_string()
}

/// Runs `pvt3 args`, which must fail: what it said on standard error.
pub fn fails(args: &[&str]) -> String {
    let out = pvt3(args);
    assert!(!out.status.success(), "pvt3 {args:?} should have failed");
    String::from_utf8_lossy(&out.stderr).to_string()
}

/// An empty folder of the system's temporary one, named for `tag` and this test process.
pub fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pvt3-cli-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
