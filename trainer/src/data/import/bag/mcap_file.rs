//! An MCAP file's topics and messages, streamed: chunks are decompressed one at a time (zstd or
//! lz4, the mcap crate's own decoders) and their CRCs checked.

use std::fs::File;
use std::io::BufReader;
use std::path::Path;

use mcap::sans_io::LinearReaderOptions;

use super::{Message, Topic};

/// The largest record a bag may hold (a chunk, or a message outside one): 1 GiB, so that a
/// damaged length cannot make the reader allocate without bound.
const RECORD_LIMIT: usize = 1 << 30;

fn reader(path: &Path) -> Result<mcap::io::MessageReader<BufReader<File>>, String> {
    let file = File::open(path).map_err(|e| e.to_string())?;
    let options = LinearReaderOptions::default()
        .with_validate_chunk_crcs(true)
        .with_validate_data_section_crc(true)
        .with_record_length_limit(RECORD_LIMIT);
    Ok(mcap::io::MessageReader::new_with_options(BufReader::new(file), options))
}

/// Its topics with their types and counts, in the order they first appear.
pub(super) fn topics(path: &Path) -> Result<Vec<Topic>, String> {
    let mut topics: Vec<Topic> = Vec::new();
    for message in reader(path)? {
        let message = message.map_err(|e| format!("not a readable MCAP file ({e})"))?;
        let channel = &message.channel;
        match topics.iter_mut().find(|t| t.name == channel.topic) {
            Some(t) => t.count += 1,
            None => topics.push(Topic {
                name: channel.topic.clone(),
                type_name: channel.schema.as_ref().map_or_else(|| "(no schema)".to_string(), |s| s.name.clone()),
                count: 1,
            }),
        }
    }
    Ok(topics)
}

/// Each message of `topic`, in the file's order.
pub(super) fn messages(path: &Path, topic: &str, each: &mut dyn FnMut(Message) -> Result<(), String>) -> Result<(), String> {
    for (k, message) in reader(path)?.enumerate() {
        let message = message.map_err(|e| format!("not a readable MCAP file after {k} records ({e})"))?;
        if message.channel.topic != topic {
            continue;
        }
        if message.channel.message_encoding != "cdr" {
            return Err(format!("topic `{topic}` is encoded as {}, not CDR", message.channel.message_encoding));
        }
        let time = i64::try_from(message.log_time).map_err(|_| format!("a receive time of {} ns", message.log_time))?;
        each(Message { time, data: message.data.into_owned() })?;
    }
    Ok(())
}

/// The receive time of its first message, if it has one.
pub(super) fn first_time(path: &Path) -> Result<Option<i64>, String> {
    match reader(path)?.next() {
        Some(message) => {
            let message = message.map_err(|e| format!("not a readable MCAP file ({e})"))?;
            Ok(Some(i64::try_from(message.log_time).map_err(|_| format!("a receive time of {} ns", message.log_time))?))
        }
        None => Ok(None),
    }
}

/// The message type of `topic`'s first message (its schema's name), if the file has one.
pub(super) fn type_of(path: &Path, topic: &str) -> Result<Option<String>, String> {
    for message in reader(path)? {
        let message = message.map_err(|e| format!("not a readable MCAP file ({e})"))?;
        if message.channel.topic == topic {
            return Ok(Some(message.channel.schema.as_ref().map_or_else(|| "(no schema)".to_string(), |s| s.name.clone())));
        }
    }
    Ok(None)
}
