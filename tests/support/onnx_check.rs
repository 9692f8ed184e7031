//! Runs `tests/onnx_check.py` (onnx checker + onnxruntime) and the tests' other Python scripts
//! from Rust tests. The first call creates a Python venv under `target/onnx-venv` and installs
//! [`PACKAGES`] into it, so the test command needs nothing but Python 3 on the machine.

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use super::workspace::workspace;

/// What the scripts import: onnx's checker and onnxruntime, numpy, the writers of ROS 2 bags
/// that `tests/bag_writer.py` uses (rosbags; mcap with mcap-ros2-support), and the zenoh peer
/// that `tests/ros_peer.py` makes of them (eclipse-zenoh; python-xxhash for rmw_zenoh's GIDs).
const PACKAGES: [&str; 8] = ["onnx", "onnxruntime", "numpy", "rosbags", "mcap", "mcap-ros2-support", "eclipse-zenoh", "xxhash"];

/// The venv's python, created once (test binaries run one after another; the venv is kept
/// across runs).
pub fn python() -> &'static Path {
    static PYTHON: OnceLock<PathBuf> = OnceLock::new();
    PYTHON.get_or_init(|| {
        let venv = workspace().canonicalize().expect("workspace root").join("target/onnx-venv");
        let python = venv.join("bin/python");
        let ready = venv.join("ready");
        let installed = PACKAGES.join(" ");
        if std::fs::read_to_string(&ready).ok().as_deref() != Some(installed.as_str()) {
            // A venv without the marker is what an interrupted install left, and one with another
            // list an older checkout's: start again.
            let _ = std::fs::remove_dir_all(&venv);
            let run = |cmd: &mut Command| {
                let out = cmd.output().expect("python3 runs");
                assert!(out.status.success(), "{cmd:?} failed:\n{}", String::from_utf8_lossy(&out.stderr));
            };
            run(Command::new("python3").args(["-m", "venv"]).arg(&venv));
            run(Command::new(&python).args(["-m", "pip", "install", "-q"]).args(PACKAGES));
            std::fs::write(&ready, &installed).expect("marker written");
        }
        python
    })
}

/// Writes `data` with `shape` as a float32 .npy file.
pub fn write_npy(path: &Path, shape: &[usize], data: &[f32]) {
    let array = ndarray::ArrayD::from_shape_vec(ndarray::IxDyn(shape), data.to_vec()).expect("shape fits data");
    ndarray_npy::write_npy(path, &array).expect("npy written");
}

/// Checks `model` with onnx and onnxruntime against `expected` (`[batch, classes]`) on `input`.
/// Panics with the checker's message unless every element is within `atol`. With `prefix`,
/// onnxruntime answers for the touch so far: the file's key bias hides every temporal token from
/// that one on (`onnx_check.py --prefix`), as a streaming runtime's provisional answer does.
pub fn assert_onnxruntime_matches(model: &Path, input: (&[usize], &[f32]), expected: &[f32], atol: f64, prefix: Option<usize>) -> String {
    let dir = model.parent().expect("model in a directory");
    let stem = model.file_stem().unwrap().to_string_lossy().to_string();
    let (x, y) = (dir.join(format!("{stem}.input.npy")), dir.join(format!("{stem}.expected.npy")));
    write_npy(&x, input.0, input.1);
    write_npy(&y, &[input.0[0], expected.len() / input.0[0]], expected);
    let (atol, tokens) = (atol.to_string(), prefix.map(|t| t.to_string()));
    let mut args: Vec<&OsStr> = vec![model.as_os_str(), x.as_os_str(), y.as_os_str(), "--atol".as_ref(), atol.as_ref()];
    if let Some(tokens) = &tokens {
        args.extend([OsStr::new("--prefix"), OsStr::new(tokens)]);
    }
    run_script("tests/onnx_check.py", &args)
}

/// Runs the Python script `script` (a path from the workspace's root) with `args` in the venv,
/// and returns what it printed; panics with its output if it fails.
pub fn run_script<A: AsRef<OsStr>>(script: &str, args: &[A]) -> String {
    let out = Command::new(python()).arg(workspace().join(script)).args(args).output().expect("the script runs");
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(out.status.success(), "{script} failed:\n{stdout}{}", String::from_utf8_lossy(&out.stderr));
    stdout
}
