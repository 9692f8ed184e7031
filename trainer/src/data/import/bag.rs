//! rosbag2 recordings, as `pvt3 import` reads them: a bag directory (its `metadata.yaml` beside
//! the `.mcap` or `.db3` files it names) or a lone `.mcap` file, one topic's messages in the
//! bag's order, each with its receive time ([`messages`]). Messages are streamed: an MCAP's
//! chunks are decompressed one at a time (zstd and lz4, their CRCs checked), SQLite's rows are
//! read as the query gives them, so a bag of any length is read in the memory of its largest
//! chunk. What a message holds is read by `pvt3_messages`, as a robot's node reads its topic.

mod mcap_file;
mod metadata;
mod sqlite;

use std::path::{Path, PathBuf};

use pvt3_messages::Kind;

/// A topic of a bag: its name, its message type and how many messages it has.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Topic {
    /// `/digit/image_raw`.
    pub name: String,
    /// `sensor_msgs/msg/Image`.
    pub type_name: String,
    /// Messages recorded.
    pub count: u64,
}

/// One message of a topic: when the bag received it (nanoseconds) and its serialised bytes.
pub struct Message {
    /// The bag's receive time, in nanoseconds.
    pub time: i64,
    /// The message, serialised (CDR).
    pub data: Vec<u8>,
}

/// The storage of one of a bag's files.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Storage {
    Mcap,
    Sqlite,
}

/// Whether `path` is a bag: a directory holding `metadata.yaml`, or an `.mcap` file.
pub fn is_bag(path: &Path) -> bool {
    (path.is_dir() && path.join(metadata::FILE).is_file())
        || (path.is_file() && path.extension().is_some_and(|e| e.eq_ignore_ascii_case("mcap")))
}

/// The files of the bag at `path`, each with its storage, in the bag's order.
fn files(path: &Path) -> Result<Vec<(PathBuf, Storage)>, String> {
    if path.is_file() {
        return Ok(vec![(path.to_path_buf(), Storage::Mcap)]);
    }
    metadata::files(path)
}

/// Every topic of the bag at `path`, with its type and message count, by name.
pub fn topics(path: &Path) -> Result<Vec<Topic>, String> {
    let mut all: Vec<Topic> = Vec::new();
    for (file, storage) in files(path)? {
        let topics = match storage {
            Storage::Mcap => mcap_file::topics(&file),
            Storage::Sqlite => sqlite::topics(&file),
        };
        for t in topics.map_err(|e| format!("{}: {e}", file.display()))? {
            match all.iter_mut().find(|a| a.name == t.name) {
                Some(a) => a.count += t.count,
                None => all.push(t),
            }
        }
    }
    all.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(all)
}

/// The kind of message `topic` of the bag at `path` carries, or why it cannot be read: the bag
/// lacks it (every topic is listed, with its type and count), or pvt3 does not read its type.
pub fn topic_kind(path: &Path, topic: Option<&str>) -> Result<(String, Kind), String> {
    let topics = topics(path)?;
    let list = || {
        let lines: Vec<String> = topics.iter().map(|t| format!("  {} ({}, {} messages)", t.name, t.type_name, t.count)).collect();
        if lines.is_empty() {
            "it has no topic".to_string()
        } else {
            format!("its topics:\n{}", lines.join("\n"))
        }
    };
    let Some(name) = topic else {
        return Err(format!("a bag needs --topic, the topic to read; {}", list()));
    };
    let found = topics.iter().find(|t| t.name == name).ok_or_else(|| format!("no topic `{name}`; {}", list()))?;
    let kind = Kind::of(&found.type_name).ok_or_else(|| {
        let known: Vec<&str> = Kind::ALL.iter().map(|(n, _)| *n).collect();
        format!("topic `{name}` carries {}, which pvt3 does not read ({})", found.type_name, known.join(", "))
    })?;
    if found.count == 0 {
        return Err(format!("topic `{name}` has no message"));
    }
    Ok((found.name.clone(), kind))
}

/// Calls `each` with every message of `topic` in the bag at `path`, in the bag's order, and
/// its index among the topic's messages; stops at the first error, `each`'s or the bag's.
pub fn messages(path: &Path, topic: &str, mut each: impl FnMut(usize, Message) -> Result<(), String>) -> Result<(), String> {
    let mut index = 0;
    for (file, storage) in files(path)? {
        let mut counted = |message: Message| {
            let at = index;
            index += 1;
            each(at, message)
        };
        match storage {
            Storage::Mcap => mcap_file::messages(&file, topic, &mut counted),
            Storage::Sqlite => sqlite::messages(&file, topic, &mut counted),
        }
        .map_err(|e| if path.is_dir() { format!("{}: {e}", file.file_name().unwrap_or_default().to_string_lossy()) } else { e })?;
    }
    Ok(())
}

#[cfg(test)]
mod tests;
