//! A file replaced whole, in one rename: written to a temporary file of this process's own beside
//! it (`NAME.PID.tmp`), then renamed over it.

use std::path::{Path, PathBuf};

use crate::{Error, Result};

/// Writes `contents` to a temporary file and renames it over `path`. The temporary file is this
/// process's own, so that jobs writing the same file at once (`cv --only` in a job array) each
/// rename a whole one.
pub fn write_file(path: &Path, contents: impl AsRef<[u8]>) -> Result<()> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(format!(".{}.tmp", std::process::id()));
    let tmp = PathBuf::from(tmp);
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
