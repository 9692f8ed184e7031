//! A camera touch from a ROS 2 bag: its topic's messages streamed twice, once to find the span
//! its frames are taken from (each frame seen once, [`Motion`]) and once to take them, so that a
//! bag of any length is read in the memory of a few frames. Each message is decoded by
//! `pvt3_messages`, as a node on the robot decodes its topic.

use std::collections::BTreeMap;
use std::path::Path;

use pvt3_format::span::Motion;
use pvt3_format::Picture;
use pvt3_messages::{decode, Frame, Kind};

use super::{enough, CameraOptions, ReadTouch};
use crate::data::import::bag::Bag;
use crate::data::import::timing::Timing;

/// The camera touch of the bag at `path`, `frames` frames of its topic as `opts` say: the
/// messages received in `window` (seconds from the bag's first message), or all of them.
pub(super) fn read(path: &Path, window: Option<(f64, f64)>, opts: &CameraOptions, frames: usize) -> Result<ReadTouch, String> {
    let bag = Bag::open(path)?;
    let (topic, kind) = bag.topic_kind(opts.topic.as_deref())?;
    if !kind.is_camera() {
        return Err(format!("topic `{topic}` carries {}, a taxel array's values, not a camera's frames", kind.name()));
    }
    // The touch's messages: their index among the topic's, and the index among the touch's.
    let within = bag.within(window)?;
    let mut motion = Motion::new(opts.span);
    let mut first: Option<Picture> = None;
    let mut times = Vec::new();
    bag.messages_within(&topic, &within, |index, message| {
        let (picture, stamp) = picture(kind, &topic, index, &message.data)?;
        times.push(stamp.unwrap_or(message.time));
        if let Some(first) = &first {
            if first.shape() != picture.shape() {
                let (now, was) = (picture.describe(), first.describe());
                return Err(format!("topic `{topic}`, message {index}: a frame of {now}, the first was {was}"));
            }
        }
        motion.push(&picture);
        first.get_or_insert(picture);
        Ok(())
    })?;
    enough(motion.frames(), frames, opts)?;
    let first = first.expect("a frame was read");
    let taken = motion.take(frames);
    let camera = opts.camera(&first);
    // The second pass keeps the frames taken (each once, however often it is taken), read.
    let mut kept: BTreeMap<usize, Option<Picture>> = taken.frames.iter().map(|&i| (i, None)).collect();
    let mut taken_so_far = 0;
    bag.messages_within(&topic, &within, |index, message| {
        if let Some(slot) = kept.get_mut(&taken_so_far) {
            *slot = Some(picture(kind, &topic, index, &message.data)?.0.read_as(&camera)?);
        }
        taken_so_far += 1;
        Ok(())
    })?;
    let chosen = taken
        .frames
        .iter()
        .map(|i| kept[i].clone().ok_or_else(|| format!("topic `{topic}` lost message {i} between two reads")))
        .collect::<Result<_, _>>()?;
    let background = if opts.subtract_first { Some(first.read_as(&camera)?) } else { None };
    let timing = Some(Timing::of(&times));
    Ok(ReadTouch { frames: chosen, background, span: (motion.frames(), taken.first, taken.last), camera, timing })
}

/// Message `index` of `topic`, a camera's, as a picture with its stamp (nanoseconds).
fn picture(kind: Kind, topic: &str, index: usize, data: &[u8]) -> Result<(Picture, Option<i64>), String> {
    let decoded = decode(kind, data).map_err(|e| format!("topic `{topic}`, message {index}: {e}"))?;
    match decoded.frame {
        Frame::Picture(p) => Ok((p, decoded.stamp.map(|s| s.nanos()))),
        Frame::Values { .. } => unreachable!("a camera's message decodes to a picture"),
    }
}
