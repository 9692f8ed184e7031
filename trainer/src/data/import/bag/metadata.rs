//! A bag directory's `metadata.yaml`, as rosbag2 writes it: the files it names (each must be
//! there) and their storage; a bag that rosbag2 compressed whole is refused, naming how.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::Storage;

/// The file rosbag2 writes beside a bag's data files.
pub const FILE: &str = "metadata.yaml";

#[derive(Deserialize)]
struct Metadata {
    rosbag2_bagfile_information: Information,
}

#[derive(Deserialize)]
struct Information {
    #[serde(default)]
    storage_identifier: String,
    #[serde(default)]
    relative_file_paths: Vec<String>,
    #[serde(default)]
    compression_format: String,
    #[serde(default)]
    compression_mode: String,
}

/// The data files the bag in `dir` names, in order, with their storage.
pub(super) fn files(dir: &Path) -> Result<Vec<(PathBuf, Storage)>, String> {
    let path = dir.join(FILE);
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let Metadata { rosbag2_bagfile_information: info } =
        serde_yaml_ng::from_str(&text).map_err(|e| format!("{FILE} is not rosbag2's ({e})"))?;
    if !info.compression_format.is_empty() && !info.compression_mode.is_empty() && info.compression_mode != "NONE" {
        return Err(format!(
            "{FILE}: the bag is compressed by rosbag2 ({}, each {}); decompress it first (`ros2 bag convert`, or record with MCAP's chunk compression instead)",
            info.compression_format,
            info.compression_mode.to_lowercase()
        ));
    }
    if info.relative_file_paths.is_empty() {
        return Err(format!("{FILE} names no data file"));
    }
    info.relative_file_paths
        .iter()
        .map(|name| {
            let file = dir.join(name);
            let storage = match (info.storage_identifier.as_str(), file.extension().and_then(|e| e.to_str())) {
                ("mcap", _) | (_, Some("mcap")) => Storage::Mcap,
                ("sqlite3", _) | (_, Some("db3")) => Storage::Sqlite,
                (other, _) => return Err(format!("{FILE}: storage `{other}` of {name}, neither mcap nor sqlite3")),
            };
            if !file.is_file() {
                return Err(format!("{FILE} names {name}, which is not there"));
            }
            Ok((file, storage))
        })
        .collect()
}
