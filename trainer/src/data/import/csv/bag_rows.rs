//! A taxel array's touch from a ROS 2 bag, read as a CSV touch is: each message of its topic (a
//! `std_msgs/msg/*MultiArray`) a frame, its values the channels `data[0]`, `data[1]`, … in the
//! message's order, and its layout's dimensions, which a grid of two takes as the sensor's rows
//! and columns. Each message is decoded by `pvt3_messages`, as a node on the robot decodes its
//! topic; every frame must hold as many values, in the same layout, as the first.

use std::path::Path;

use pvt3_messages::{decode, Frame};

use crate::data::import::bag::Bag;
use crate::data::import::timing::Timing;

/// A bag's touch: its frames' values, their layout, and how their times strayed.
pub(super) struct BagRows {
    /// The layout's dimensions, outermost first (none where the messages give none).
    pub(super) dims: Vec<usize>,
    /// A row a message, its values.
    pub(super) rows: Vec<Vec<f32>>,
    /// The messages' receive times (a multi-array has no header), counted.
    pub(super) timing: Timing,
}

/// The channel name of a message's value `k`: the field as `ros2 topic echo` shows it.
pub(super) fn channel(k: usize) -> String {
    format!("data[{k}]")
}

/// The messages of `topic` (a taxel array's) in the bag at `path` received in `window`
/// (seconds from the bag's first message), or all of them.
pub(super) fn read(path: &Path, window: Option<(f64, f64)>, topic: Option<&str>) -> Result<BagRows, String> {
    let bag = Bag::open(path)?;
    let (topic, kind) = bag.topic_kind(topic)?;
    if kind.is_camera() {
        return Err(format!("topic `{topic}` carries {}, a camera's frames, and this folder holds CSV touches", kind.name()));
    }
    let within = bag.within(window)?;
    let (mut rows, mut times, mut dims) = (Vec::new(), Vec::new(), None);
    bag.messages_within(&topic, &within, |index, message| {
        let at = || format!("topic `{topic}`, message {index}");
        let decoded = decode(kind, &message.data).map_err(|e| format!("{}: {e}", at()))?;
        let Frame::Values { values, dims: layout } = decoded.frame else { unreachable!("a multi-array decodes to values") };
        if let Some(k) = values.iter().position(|v| !v.is_finite()) {
            return Err(format!("{}: data[{k}] is {}, not a reading (a data set holds finite 32-bit floats)", at(), values[k]));
        }
        let first: &(usize, Vec<usize>) = dims.get_or_insert_with(|| (values.len(), layout.clone()));
        if (values.len(), &layout) != (first.0, &first.1) {
            return Err(format!(
                "{}: {} values in layout {layout:?}; the touch's first message has {} in {:?}",
                at(),
                values.len(),
                first.0,
                first.1
            ));
        }
        if values.is_empty() {
            return Err(format!("{}: no value", at()));
        }
        rows.push(values);
        times.push(decoded.stamp.map_or(message.time, |s| s.nanos()));
        Ok(())
    })?;
    let Some((_, dims)) = dims else { return Err(format!("topic `{topic}` has no message: an empty touch")) };
    Ok(BagRows { dims, rows, timing: Timing::of(&times) })
}
