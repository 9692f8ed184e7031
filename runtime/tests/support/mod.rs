//! What the runtime's end-to-end tests share: the committed golden model and its vectors, scratch
//! directories, and running a program built for the target (under the emulator that
//! `PVT3_TARGET_RUNNER` names when the tests run for another architecture, as `tests/run.sh`
//! does for aarch64).

#![allow(dead_code)] // each test file uses part of it

use std::path::{Path, PathBuf};
#[path = "../../../tests/support/target.rs"]
mod target;
#[allow(unused_imports)] // each test file uses part of it
pub use target::{emulated, target_command};

pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf()
}

/// A file of the committed golden iCub model (`tests/golden/icub20`).
pub fn golden(file: &str) -> PathBuf {
    root().join("../tests/golden/icub20").join(file)
}

/// A fresh directory for one test.
pub fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pvt3-runtime-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// How many of the golden input's eight windows a test streams frame by frame: two under an
/// emulator, all eight on the host.
pub fn streamed_windows() -> usize {
    if emulated() {
        2
    } else {
        8
    }
}

/// The C compiler for the target: `TARGET_CC` (as the `cc` crate reads it when cross-compiling),
/// else `CC`, else `cc`.
pub fn target_cc() -> String {
    std::env::var("TARGET_CC").or_else(|_| std::env::var("CC")).unwrap_or_else(|_| "cc".into())
}

/// The golden input, `[8, 6, 10, 75]`, and logits, `[8, 20]`.
pub fn golden_vectors() -> (Vec<f32>, Vec<f32>) {
    let (shape, x) = pvt3_runtime::read_npy(&golden("input.npy")).unwrap();
    assert_eq!(shape, vec![8, 6, 10, 75]);
    let (shape, logits) = pvt3_runtime::read_npy(&golden("logits.npy")).unwrap();
    assert_eq!(shape, vec![8, 20]);
    (x, logits)
}

/// Deterministic pseudo-random numbers below `n` (xorshift), for the damaged-file tests.
pub struct Draw(pub u64);

impl Draw {
    pub fn below(&mut self, n: usize) -> usize {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 % n.max(1) as u64) as usize
    }
}

/// The shipped camera file re-signed after its first initializer was emptied with a wild
/// dimension (`[2⁵⁰, 0]`): a file that holds what its dimensions say (nothing) but whose size
/// no reader can allocate. Before sizes were checked, tract panicked on such files. The
/// initializer's name is returned beside the bytes.
pub fn damaged_camera_file() -> (Vec<u8>, String) {
    use prost::Message;
    let bytes = std::fs::read(root().join("../shipped/physiclear.onnx")).unwrap();
    let mut model = pvt3_format::onnx::ModelProto::decode(bytes.as_slice()).unwrap();
    let t = &mut model.graph.as_mut().unwrap().initializer[0];
    (t.dims, t.raw_data) = (vec![1 << 50, 0], Vec::new());
    let name = t.name.clone();
    model.sign();
    (model.encode_to_vec(), name)
}
