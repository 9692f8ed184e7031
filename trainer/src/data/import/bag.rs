//! rosbag2 recordings, as `pvt3 import` reads them: a bag directory (its `metadata.yaml` beside
//! the `.mcap` or `.db3` files it names, read once when the [`Bag`] is opened) or a lone `.mcap`
//! file, one topic's messages in the bag's order, each with its receive time
//! ([`Bag::messages_within`], a touch's window of them). Messages are streamed: an MCAP's
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

/// A bag: where it is and its files, each with its storage, in the bag's order.
pub struct Bag {
    path: PathBuf,
    files: Vec<(PathBuf, Storage)>,
}

impl Bag {
    /// The bag at `path`: its `metadata.yaml` read, every file it names there.
    pub fn open(path: &Path) -> Result<Self, String> {
        let files = if path.is_file() { vec![(path.to_path_buf(), Storage::Mcap)] } else { metadata::files(path)? };
        Ok(Self { path: path.to_path_buf(), files })
    }

    /// Every topic of the bag, with its type and message count, by name.
    pub fn topics(&self) -> Result<Vec<Topic>, String> {
        let mut all: Vec<Topic> = Vec::new();
        for (file, storage) in &self.files {
            let topics = match storage {
                Storage::Mcap => mcap_file::topics(file),
                Storage::Sqlite => sqlite::topics(file),
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

    /// The kind of message `topic` carries, or why it cannot be read: the bag has no message on it
    /// (every topic is then listed, with its type and count), or pvt3 does not read its type. The
    /// type is that of the topic's first message, found without reading the rest of the bag.
    pub fn topic_kind(&self, topic: Option<&str>) -> Result<(String, Kind), String> {
        let listed = || -> Result<String, String> {
            let topics = self.topics()?;
            let lines: Vec<String> = topics.iter().map(|t| format!("  {} ({}, {} messages)", t.name, t.type_name, t.count)).collect();
            Ok(if lines.is_empty() { "it has no topic".to_string() } else { format!("its topics:\n{}", lines.join("\n")) })
        };
        let Some(name) = topic else {
            return Err(format!("a bag needs --topic, the topic to read; {}", listed()?));
        };
        let mut type_name = None;
        for (file, storage) in &self.files {
            type_name = match storage {
                Storage::Mcap => mcap_file::type_of(file, name),
                Storage::Sqlite => sqlite::type_of(file, name),
            }
            .map_err(|e| format!("{}: {e}", file.display()))?;
            if type_name.is_some() {
                break;
            }
        }
        let type_name = type_name.ok_or_else(|| match listed() {
            Ok(list) => format!("no message on topic `{name}`; {list}"),
            Err(e) => e,
        })?;
        let kind = Kind::of(&type_name).ok_or_else(|| {
            let known: Vec<&str> = Kind::ALL.iter().map(|(n, _)| *n).collect();
            format!("topic `{name}` carries {type_name}, which pvt3 does not read ({})", known.join(", "))
        })?;
        Ok((name.to_string(), kind))
    }

    /// The messages received from `window.0` to `window.1` seconds (the end excluded) after the
    /// bag's first message (its first file's first message), or every message.
    pub fn within(&self, window: Option<(f64, f64)>) -> Result<Within, String> {
        let Some((start, end)) = window else { return Ok(Within { window: None, seconds: (0.0, f64::INFINITY) }) };
        let (file, storage) = self.files.first().expect("a bag names a file");
        let first = match storage {
            Storage::Mcap => mcap_file::first_time(file),
            Storage::Sqlite => sqlite::first_time(file),
        }?
        .ok_or("the bag has no message")?;
        let at = |s: f64| first.saturating_add((s * 1e9).round() as i64);
        Ok(Within { window: Some((at(start), at(end))), seconds: (start, end) })
    }

    /// Calls `each` with the messages of `topic` that `within` holds, as [`Bag::messages`] does;
    /// refuses a window of seconds that holds none.
    pub fn messages_within(
        &self,
        topic: &str,
        within: &Within,
        mut each: impl FnMut(usize, Message) -> Result<(), String>,
    ) -> Result<(), String> {
        let mut taken = 0;
        self.messages(topic, |index, message| {
            if !within.holds(message.time) {
                return Ok(());
            }
            taken += 1;
            each(index, message)
        })?;
        if taken == 0 && within.window.is_some() {
            let (start, end) = within.seconds;
            return Err(format!("topic `{topic}` has no message from {start} s to {end} s of the bag"));
        }
        Ok(())
    }

    /// Calls `each` with every message of `topic`, in the bag's order, and its index among the
    /// topic's messages; stops at the first error, `each`'s or the bag's.
    fn messages(&self, topic: &str, mut each: impl FnMut(usize, Message) -> Result<(), String>) -> Result<(), String> {
        let mut index = 0;
        for (file, storage) in &self.files {
            let mut counted = |message: Message| {
                let at = index;
                index += 1;
                each(at, message)
            };
            match storage {
                Storage::Mcap => mcap_file::messages(file, topic, &mut counted),
                Storage::Sqlite => sqlite::messages(file, topic, &mut counted),
            }
            .map_err(|e| {
                if self.path.is_dir() {
                    format!("{}: {e}", file.file_name().unwrap_or_default().to_string_lossy())
                } else {
                    e
                }
            })?;
        }
        Ok(())
    }
}

/// Which messages of a bag a touch takes: those received within a window of seconds from the
/// bag's first message (its first file's first message), or all of them ([`Bag::within`]).
pub struct Within {
    window: Option<(i64, i64)>,
    seconds: (f64, f64),
}

impl Within {
    /// Whether a message received at `time` (nanoseconds) is the touch's.
    fn holds(&self, time: i64) -> bool {
        self.window.is_none_or(|(start, end)| (start..end).contains(&time))
    }
}

#[cfg(test)]
mod tests;
