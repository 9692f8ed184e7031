//! Files and directories replaced whole: written under a temporary name beside the target, then
//! renamed over it, so that a reader never sees half of one and a crash leaves the previous
//! version. A directory takes two renames; if a crash strikes between them, the previous version
//! is found under `NAME.old` ([`existing_dir`]). Below everything a run stores: checkpoints, JSON
//! records, pictures.

use std::path::{Path, PathBuf};

use crate::{Error, Result};

/// Writes `contents` to a temporary file and renames it over `path`. The temporary file is this
/// process's own, so that jobs writing the same file at once (`cv --only` in a job array) each
/// rename a whole one.
pub fn write_file(path: &Path, contents: impl AsRef<[u8]>) -> Result<()> {
    let tmp = sibling(path, &format!(".{}.tmp", std::process::id()));
    std::fs::write(&tmp, contents).map_err(Error::io(&tmp))?;
    std::fs::rename(&tmp, path).map_err(Error::io(path))
}

/// Removes the temporary files (`*.tmp`) under `dir`: a process killed between writing one and
/// renaming it leaves it behind. Only for a directory one process writes, such as a run's.
pub fn remove_temporaries(dir: &Path) -> Result<()> {
    let Ok(entries) = std::fs::read_dir(dir) else { return Ok(()) };
    for entry in entries {
        let path = entry.map_err(Error::io(dir))?.path();
        if path.is_dir() {
            remove_temporaries(&path)?;
        } else if path.extension().is_some_and(|e| e == "tmp") {
            std::fs::remove_file(&path).map_err(Error::io(&path))?;
        }
    }
    Ok(())
}

/// The path beside `target` with `suffix` added to its name: where a file or directory is written
/// before it is renamed over `target` (`.tmp`), or kept while it is replaced (`.old`).
fn sibling(target: &Path, suffix: &str) -> PathBuf {
    let mut name = target.file_name().expect("a file or directory name").to_os_string();
    name.push(suffix);
    target.with_file_name(name)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_killed_writes_temporaries_are_removed_and_nothing_else() {
        let dir = std::env::temp_dir().join(format!("pvt3-temporaries-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("model")).unwrap();
        let names = ["curves.svg", "curves.svg.41.tmp", "model/provenance.json", "model/provenance.json.7.tmp", "metrics.jsonl"];
        for name in names {
            std::fs::write(dir.join(name), "x").unwrap();
        }
        remove_temporaries(&dir).unwrap();
        let left: Vec<bool> = names.iter().map(|n| dir.join(n).exists()).collect();
        assert_eq!(left, [true, false, true, false, true]);
        remove_temporaries(&dir.join("absent")).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
