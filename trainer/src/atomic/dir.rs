//! A directory replaced whole, in two renames: filled under `NAME.tmp`, the previous version moved
//! to `NAME.old`, the new one renamed in. If a crash strikes between the renames, the previous
//! version is found under `NAME.old` ([`existing_dir`]).

use std::path::{Path, PathBuf};

use crate::{Error, Result};

/// The path beside `target` with `suffix` added to its name: where the directory is filled before
/// it is renamed over `target` (`.tmp`), or kept while it is replaced (`.old`).
fn sibling(target: &Path, suffix: &str) -> PathBuf {
    let mut path = target.as_os_str().to_owned();
    path.push(suffix);
    path.into()
}

/// Writes a directory through `fill` under a temporary name, then swaps it in for `target`.
pub fn replace_dir(target: &Path, fill: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let tmp = sibling(target, ".tmp");
    let old = sibling(target, ".old");
    if tmp.exists() {
        std::fs::remove_dir_all(&tmp).map_err(Error::io(&tmp))?;
    }
    std::fs::create_dir_all(&tmp).map_err(Error::io(&tmp))?;
    fill(&tmp)?;
    crate::crash::point("filled");
    if target.exists() {
        if old.exists() {
            std::fs::remove_dir_all(&old).map_err(Error::io(&old))?;
        }
        std::fs::rename(target, &old).map_err(Error::io(target))?;
    }
    crate::crash::point("swapping");
    std::fs::rename(&tmp, target).map_err(Error::io(&tmp))?;
    if old.exists() {
        std::fs::remove_dir_all(&old).map_err(Error::io(&old))?;
    }
    Ok(())
}

/// The directory to read for `target`: itself, or the `.old` copy a crash left behind.
pub fn existing_dir(target: &Path) -> Option<PathBuf> {
    let old = sibling(target, ".old");
    if target.is_dir() {
        Some(target.to_path_buf())
    } else if old.is_dir() {
        Some(old)
    } else {
        None
    }
}
