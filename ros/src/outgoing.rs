//! The messages the node publishes, in CDR by their definitions ([`crate::interfaces`]): each
//! touch's answer (`vision_msgs/msg/Classification`), how it was reached
//! (`diagnostic_msgs/msg/DiagnosticStatus`) and what went wrong (`rcl_interfaces/msg/Log`, on
//! `/rosout`).

use pvt3_messages::cdr::Writer;
use pvt3_messages::Stamp;

/// `std_msgs/msg/Header`.
fn header(w: &mut Writer, stamp: Stamp, frame_id: &str) {
    w.write(stamp.sec).write(stamp.nanosec).string(frame_id);
}

/// A touch's answer: one hypothesis a class, in the file's order, with its probability.
pub fn classification(stamp: Stamp, frame_id: &str, classes: &[String], probabilities: &[f32]) -> Vec<u8> {
    let mut w = Writer::new();
    header(&mut w, stamp, frame_id);
    w.length(classes.len());
    for (class, p) in classes.iter().zip(probabilities) {
        w.string(class).write(f64::from(*p));
    }
    w.finish()
}

/// How a touch's answer was reached, as `diagnostic_msgs/msg/DiagnosticStatus` (level OK): its
/// message says the class and the frames read; its values are `class`, `frames` (read),
/// `window` (the file's frames), `early_stop` (`true` where the stopping rule decided before the
/// window was full), `ended_by` (`window`, `early_stop`, `contact` or `reset`) and
/// `compute_ms` (the runtime's time over the touch, milliseconds) and `last_ms` (its time on the
/// message that ended the touch, from its arrival to the answer: what a publish-to-answer
/// latency is held against).
#[derive(Clone, Debug, PartialEq)]
pub struct Status {
    /// The class answered.
    pub class: String,
    /// Frames read.
    pub frames: usize,
    /// The file's frames a touch.
    pub window: usize,
    /// Whether the stopping rule decided before the window was full.
    pub early_stop: bool,
    /// What ended the touch.
    pub ended_by: &'static str,
    /// The runtime's time over the touch, in milliseconds.
    pub compute_ms: f64,
    /// The runtime's time on the message that ended the touch, in milliseconds.
    pub last_ms: f64,
}

/// The status message of node `name`.
pub fn status(name: &str, s: &Status) -> Vec<u8> {
    let mut w = Writer::new();
    w.write(0u8).string(name).string(&format!("{} after {} of {} frames", s.class, s.frames, s.window)).string("");
    let values = [
        ("class", s.class.clone()),
        ("frames", s.frames.to_string()),
        ("window", s.window.to_string()),
        ("early_stop", s.early_stop.to_string()),
        ("ended_by", s.ended_by.to_string()),
        ("compute_ms", format!("{:.3}", s.compute_ms)),
        ("last_ms", format!("{:.3}", s.last_ms)),
    ];
    w.length(values.len());
    for (key, value) in values {
        w.string(key).string(&value);
    }
    w.finish()
}

/// `rcl_interfaces/msg/Log`'s levels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Level {
    /// 20.
    Info = 20,
    /// 30.
    Warn = 30,
}

/// A line of the node's log, for `/rosout`.
pub fn log(stamp: Stamp, level: Level, name: &str, text: &str) -> Vec<u8> {
    let mut w = Writer::new();
    w.write(stamp.sec).write(stamp.nanosec).write(level as u8).string(name).string(text).string(file!()).string("").write(0u32);
    w.finish()
}

#[cfg(test)]
mod tests {
    use pvt3_messages::cdr::Reader;

    use super::*;

    #[test]
    fn a_classification_holds_every_class_with_its_probability() {
        let m = classification(Stamp { sec: 5, nanosec: 6 }, "digit", &["felt".into(), "wood".into()], &[0.25, 0.75]);
        let mut r = Reader::new(&m).unwrap();
        assert_eq!((r.read::<i32>("sec").unwrap(), r.read::<u32>("nanosec").unwrap(), r.string("frame").unwrap()), (5, 6, "digit".into()));
        assert_eq!(r.length("results").unwrap(), 2);
        assert_eq!((r.string("class").unwrap(), r.read::<f64>("score").unwrap()), ("felt".into(), 0.25));
        assert_eq!((r.string("class").unwrap(), r.read::<f64>("score").unwrap()), ("wood".into(), 0.75));
    }
}
