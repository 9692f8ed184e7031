//! A training run killed outright (SIGKILL: no cleanup, no flush) at moments spread over its
//! epochs, so while it steps, validates and writes its checkpoints, and resumed (`--resume`) each
//! time until it ends, leaves the very files an uninterrupted run leaves: weights, optimiser
//! states, checkpoints, metrics and pictures, the wall-clock seconds they record aside.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

use ndarray::{Array1, ArrayD, IxDyn};
use ndarray_npy::NpzWriter;

#[path = "support/pvt3_command.rs"]
#[allow(dead_code)] // the other end-to-end tests use the rest of it
mod pvt3_command;
#[path = "support/workspace.rs"]
mod workspace;

use pvt3_command::{scratch, succeeds};

/// Kills before the run is let finish.
const KILLS: usize = 16;
/// The run's epochs.
const EPOCHS: usize = 20;

#[test]
fn a_run_killed_anywhere_resumes_to_the_same_bytes() {
    let dir = scratch("kill");
    let data = tiny_set(&dir);
    let args = |out: &Path| -> Vec<String> {
        let d = data.to_str().unwrap();
        let small =
            ["--epochs", &EPOCHS.to_string(), "--batch-size", "8", "--set", "space_depth=1", "--set", "time_depth=1", "--set", "dim=8"];
        let mut args: Vec<String> = ["train", "--data", d, "--out", out.to_str().unwrap()].iter().map(|s| s.to_string()).collect();
        args.extend(small.iter().map(|s| s.to_string()));
        args
    };
    // Both runs train in one directory (a run's pictures name it), the first moved aside after.
    let (killed, whole) = (dir.join("run"), dir.join("whole"));
    let started = Instant::now();
    succeeds(&args(&killed).iter().map(String::as_str).collect::<Vec<_>>());
    let took = started.elapsed();
    std::fs::rename(&killed, &whole).unwrap();

    let mut rng = pvt3_spec::Rng::new(11);
    let logged = || std::fs::read_to_string(killed.join("metrics.jsonl")).map_or(0, |m| m.lines().count());
    let epoch = took.div_f64(EPOCHS as f64);
    // The epochs the run had logged at each kill that caught it training (between its first
    // and its last epoch).
    let mut caught = std::collections::BTreeSet::new();
    for k in 0..KILLS {
        let before = logged();
        if before >= EPOCHS {
            break;
        }
        let mut run = args(&killed);
        if k > 0 {
            run.push("--resume".into());
        }
        let mut child = quiet(&run).spawn().unwrap();
        // Each call is let log an epoch more, then lives a random share of an epoch's time, so
        // that the run advances between kills however busy the machine is, and is caught at a
        // different moment of an epoch each time: stepping, validating, writing its checkpoint
        // or its resume state. (A share of the whole run's time caught it at the same epoch
        // again and again when a load beside slowed its start-up.)
        let deadline = Instant::now() + 3 * took;
        while logged() <= before && child.try_wait().unwrap().is_none() && Instant::now() < deadline {
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
        std::thread::sleep(epoch.mul_f64(rng.uniform() as f64));
        // SIGKILL: what a power cut or the out-of-memory killer does.
        let _ = child.kill();
        child.wait().unwrap();
        let done = logged();
        if (1..EPOCHS).contains(&done) {
            caught.insert(done);
        }
    }
    assert!(caught.len() >= 3, "the kills caught the run training after {caught:?} epochs alone: too few to test");
    let mut resume = args(&killed);
    resume.push("--resume".into());
    succeeds(&resume.iter().map(String::as_str).collect::<Vec<_>>());
    same_files(&whole, &killed);

    // Then at each stage where a kill's moment matters, aborted there (`PVT3_CRASH_AT`): after
    // an epoch's steps, after its validation (its checkpoint written), after its metrics line,
    // with a new checkpoint or resume state written but not yet swapped in, between the swap's
    // two renames, and after the resume state.
    for stage in ["stepped", "validated", "logged", "filled", "swapping", "saved"] {
        for pass in [2, 7] {
            let _ = std::fs::remove_dir_all(&killed);
            let crashed = quiet(&args(&killed)).env(pvt3_trainer::crash::CRASH_AT, format!("{stage}:{pass}")).status().unwrap();
            assert!(!crashed.success(), "{stage}:{pass} did not abort");
            succeeds(&resume.iter().map(String::as_str).collect::<Vec<_>>());
            same_files(&whole, &killed);
        }
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// `pvt3 args` from the workspace's root, saying nothing.
fn quiet(args: &[String]) -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_pvt3"));
    command.args(args).current_dir(workspace::workspace()).stdin(Stdio::null()).stdout(Stdio::null()).stderr(Stdio::null());
    command
}

/// Two classes of twenty touches, 4 channels of 32 frames.
fn tiny_set(dir: &Path) -> PathBuf {
    let n = 40;
    let mut rng = pvt3_spec::Rng::new(5);
    let x: Vec<f32> = (0..n * 4 * 32).map(|i| ((i / 128) % 2) as f32 * ((i % 32) as f32 * 0.4).sin() + 0.5 * rng.normal()).collect();
    let path = dir.join("tiny.npz");
    let mut w = NpzWriter::new(std::fs::File::create(&path).unwrap());
    w.add_array("x", &ArrayD::from_shape_vec(IxDyn(&[n, 4, 32]), x).unwrap()).unwrap();
    w.add_array("y", &Array1::from_iter((0..n).map(|i| (i % 2) as i64))).unwrap();
    w.finish().unwrap();
    path
}

/// Every file under `dir`, relative to it, sorted.
fn files(dir: &Path, root: &Path) -> Vec<PathBuf> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            found.extend(files(&path, root));
        } else {
            found.push(path.strip_prefix(root).unwrap().to_path_buf());
        }
    }
    found.sort();
    found
}

/// Asserts that `a` and `b` hold the same files with the same bytes, but for the wall-clock
/// seconds a JSON file records.
fn same_files(a: &Path, b: &Path) {
    let names = files(a, a);
    assert_eq!(names, files(b, b), "the same files");
    for name in names {
        let (x, y) = (std::fs::read(a.join(&name)).unwrap(), std::fs::read(b.join(&name)).unwrap());
        if x == y {
            continue;
        }
        let untimed = |bytes: &[u8]| -> Vec<serde_json::Value> {
            let text = String::from_utf8(bytes.to_vec()).unwrap_or_else(|_| panic!("{} differs", name.display()));
            text.lines().filter(|l| !l.trim().is_empty()).map(|l| drop_times(serde_json::from_str(l).unwrap())).collect()
        };
        let json = |bytes: &[u8]| -> Vec<serde_json::Value> {
            match name.extension().and_then(|e| e.to_str()) {
                Some("jsonl") => untimed(bytes),
                Some("json") => vec![drop_times(serde_json::from_slice(bytes).unwrap())],
                _ => panic!("{} differs", name.display()),
            }
        };
        assert_eq!(json(&x), json(&y), "{} differs but for seconds", name.display());
    }
}

fn drop_times(v: serde_json::Value) -> serde_json::Value {
    match v {
        serde_json::Value::Object(m) => {
            m.into_iter().filter(|(k, _)| k != "seconds" && k != "wall_seconds").map(|(k, v)| (k, drop_times(v))).collect()
        }
        serde_json::Value::Array(a) => a.into_iter().map(drop_times).collect(),
        other => other,
    }
}
