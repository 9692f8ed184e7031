//! A rosbag2 SQLite file (`.db3`, the storage before Jazzy): its `topics` and `messages` tables,
//! the messages read row by row as the query gives them, in receive-time order.

use std::path::Path;

use rusqlite::{Connection, OpenFlags};

use super::{Message, Topic};

fn open(path: &Path) -> Result<Connection, String> {
    let connection = Connection::open_with_flags(path, OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX)
        .map_err(|e| format!("not a readable SQLite file ({e})"))?;
    // A damaged file is refused where SQLite finds it so, before any message is read.
    let check: String =
        connection.query_row("PRAGMA quick_check", [], |r| r.get(0)).map_err(|e| format!("not a readable SQLite bag ({e})"))?;
    if check != "ok" {
        return Err(format!("a damaged SQLite file ({check})"));
    }
    Ok(connection)
}

fn bad(e: rusqlite::Error) -> String {
    format!("not a readable rosbag2 SQLite file ({e})")
}

/// Its topics with their types and counts.
pub(super) fn topics(path: &Path) -> Result<Vec<Topic>, String> {
    let connection = open(path)?;
    let mut query = connection
        .prepare("SELECT topics.name, topics.type, (SELECT COUNT(*) FROM messages WHERE messages.topic_id = topics.id) FROM topics")
        .map_err(bad)?;
    let rows = query.query_map([], |r| Ok(Topic { name: r.get(0)?, type_name: r.get(1)?, count: r.get::<_, i64>(2)?.max(0) as u64 }));
    let topics = rows.map_err(bad)?.collect::<Result<Vec<_>, _>>().map_err(bad)?;
    Ok(topics)
}

/// Each message of `topic`, in receive-time order (ties in the order recorded).
pub(super) fn messages(path: &Path, topic: &str, each: &mut dyn FnMut(Message) -> Result<(), String>) -> Result<(), String> {
    let connection = open(path)?;
    let format: Option<String> = connection
        .query_row("SELECT serialization_format FROM topics WHERE name = ?1", [topic], |r| r.get(0))
        .map_err(|e| format!("topic `{topic}`: {e}"))?;
    if let Some(format) = format.filter(|f| f != "cdr") {
        return Err(format!("topic `{topic}` is encoded as {format}, not CDR"));
    }
    let mut query = connection
        .prepare("SELECT messages.timestamp, messages.data FROM messages JOIN topics ON messages.topic_id = topics.id WHERE topics.name = ?1 ORDER BY messages.timestamp, messages.id")
        .map_err(bad)?;
    let mut rows = query.query([topic]).map_err(bad)?;
    while let Some(row) = rows.next().map_err(bad)? {
        each(Message { time: row.get(0).map_err(bad)?, data: row.get(1).map_err(bad)? })?;
    }
    Ok(())
}

/// The receive time of its first message, if it has one.
pub(super) fn first_time(path: &Path) -> Result<Option<i64>, String> {
    open(path)?.query_row("SELECT MIN(timestamp) FROM messages", [], |r| r.get(0)).map_err(bad)
}

/// The message type of `topic`, if the file has a message on it.
pub(super) fn type_of(path: &Path, topic: &str) -> Result<Option<String>, String> {
    let connection = open(path)?;
    let mut query = connection
        .prepare("SELECT type FROM topics WHERE name = ?1 AND EXISTS (SELECT 1 FROM messages WHERE messages.topic_id = topics.id)")
        .map_err(bad)?;
    let found = query.query_row([topic], |r| r.get(0));
    match found {
        Ok(t) => Ok(Some(t)),
        Err(rusqlite::Error::QueryReturnedNoRows) => Ok(None),
        Err(e) => Err(bad(e)),
    }
}
