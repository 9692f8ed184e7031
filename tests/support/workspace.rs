//! Where the end-to-end tests find the shipped data, fixtures, golden files and scripts.

use std::path::{Path, PathBuf};

/// The workspace's root (every crate is one level below it).
pub fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}
