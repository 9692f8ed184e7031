//! A touch as the node follows it: each decoded message pushed through the runtime's session
//! as the file says its frames are read (a camera's frames cropped, shrunk and greyed, the
//! touch's first kept as its background; a taxel array's values as the grid), until the touch
//! ends: the window is full, the file's stopping rule decides early, contact is lost, or a reset
//! comes. A camera's touch may instead be a recording whose frames are taken over the span in
//! which the gel moves, as `pvt3 import` takes a video's ([`Boundary::Moving`]). Free of any
//! transport, so that its answers are tested against `pvt3-run`'s alone.

use std::time::{Duration, Instant};

use pvt3_format::span::{FrameSpan, Motion};
use pvt3_messages::{Decoded, Frame, Stamp};
use pvt3_runtime::{Classifier, Picture, Prediction, Session};

use crate::outgoing::Status;

/// When a touch begins and ends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Boundary {
    /// Every frame belongs to a touch; one ends when the window is full (or the stopping rule
    /// decides), and the next frame begins the next.
    Frames,
    /// A touch begins when the contact topic says `true` and ends when it says `false` (or the
    /// window is full, or the stopping rule decides); frames out of contact are dropped.
    Contact,
    /// A camera's: every frame is recorded, each read as the file says, until the recording
    /// holds this many frames or contact is lost; the window's frames are then taken evenly over
    /// the span in which the gel moves, as `pvt3 import` takes a video's, less the recording's
    /// first frame where the file was trained so. The stopping rule does not apply.
    Moving(usize),
}

/// A recording for [`Boundary::Moving`]: what the moving span needs of each frame, each frame
/// read as the file says (a model's frame, far smaller than the camera's) and its stamp.
struct Recording {
    motion: Motion,
    read: Vec<Picture>,
    stamps: Vec<Stamp>,
}

impl Default for Recording {
    /// Nothing recorded yet.
    fn default() -> Self {
        Self { motion: Motion::new(FrameSpan::Moving), read: Vec::new(), stamps: Vec::new() }
    }
}

/// A touch's answer: the prediction, the stamp of its last frame, and how it was reached.
#[derive(Clone, Debug, PartialEq)]
pub struct Answer {
    /// The prediction.
    pub prediction: Prediction,
    /// The last frame's stamp (`header.stamp`, or when the node received it).
    pub stamp: Stamp,
    /// How it was reached.
    pub status: Status,
}

/// The touch in progress and how touches are cut.
pub struct Touches {
    classifier: Classifier,
    session: Session,
    boundary: Boundary,
    early_stop: bool,
    in_contact: bool,
    /// Frames pushed in this touch, the last one's stamp, and the runtime's time so far.
    frames: usize,
    last: Stamp,
    compute: Duration,
    /// When the runtime began on the message that ends the touch (a frame, or losing contact).
    last_began: Instant,
    /// The GID of the publisher whose frames make the touch, where its messages say.
    source: Option<[u8; 16]>,
    recording: Recording,
}

/// Why a message was not taken; the node reports it and keeps serving.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct Refused(pub String);

/// Why touches cannot be cut as asked, for this file.
#[derive(Debug, thiserror::Error)]
pub enum TouchesError {
    /// The runtime refused the file.
    #[error(transparent)]
    Runtime(#[from] pvt3_runtime::Error),
    /// The boundary does not suit the file.
    #[error("{0}")]
    Boundary(String),
}
use TouchesError::Boundary as BoundaryError;

impl Touches {
    /// Touches of `classifier`'s file cut at `boundary`, answered early where `early_stop` and the
    /// file's stopping rule say so.
    pub fn new(classifier: Classifier, boundary: Boundary, early_stop: bool) -> Result<Self, TouchesError> {
        let session = classifier.session()?;
        let early_stop = early_stop && classifier.stop_rule().is_some();
        if let Boundary::Moving(frames) = boundary {
            let window = session.frames();
            if classifier.camera().is_none() {
                return Err(BoundaryError("touch:=moving takes a camera's recording; this file reads a taxel array's values".into()));
            }
            if frames < window {
                return Err(BoundaryError(format!("recording:={frames}: a recording must hold the window's {window} frames at least")));
            }
        }
        Ok(Self {
            classifier,
            session,
            boundary,
            early_stop,
            in_contact: false,
            frames: 0,
            last: Stamp::default(),
            compute: Duration::ZERO,
            last_began: Instant::now(),
            source: None,
            recording: Recording::default(),
        })
    }

    /// The file's classifier.
    pub fn classifier(&self) -> &Classifier {
        &self.classifier
    }

    /// Takes a decoded message received at `received` from the publisher `source` (its GID,
    /// where the message says); the touch's answer if it ends the touch. Within a touch, a frame
    /// of a second publisher, or stamped before the frame before it, is refused: neither can be
    /// put in its place in a stream.
    pub fn frame(&mut self, decoded: Decoded, received: Stamp, source: Option<[u8; 16]>) -> Result<Option<Answer>, Refused> {
        if self.boundary == Boundary::Contact && !self.in_contact {
            return Ok(None);
        }
        if self.frames > 0 {
            if source.is_some() && self.source.is_some() && source != self.source {
                return Err(Refused(format!("a second publisher's frame, dropped: the touch is the first's ({} frames in)", self.frames)));
            }
            if let Some(stamp) = decoded.stamp.filter(|s| *s < self.last) {
                let at = |s: Stamp| format!("{}.{:09}", s.sec, s.nanosec);
                return Err(Refused(format!("a frame stamped {}, before the one before it ({}): dropped", at(stamp), at(self.last))));
            }
        } else {
            self.source = source;
        }
        if let Boundary::Moving(frames) = self.boundary {
            return self.record(decoded, received, frames);
        }
        let started = Instant::now();
        self.last_began = started;
        self.push(decoded.frame)?;
        self.compute += started.elapsed();
        self.frames += 1;
        self.last = decoded.stamp.unwrap_or(received);
        if self.session.received() == self.session.frames() {
            return self.finish("window").map(Some);
        }
        let tubelet = self.classifier.tubelet();
        if self.early_stop && self.session.received() > 0 && self.session.received().is_multiple_of(tubelet) {
            let started = Instant::now();
            let peek = self.session.peek().map_err(|e| Refused(e.to_string()))?;
            self.compute += started.elapsed();
            if peek.stop {
                return Ok(Some(self.answer(peek.prediction, "early_stop")));
            }
        }
        Ok(None)
    }

    /// Pushes a frame into the session as the file reads its frames.
    fn push(&mut self, frame: Frame) -> Result<(), Refused> {
        let pushed = match frame {
            Frame::Values { values, .. } if self.classifier.camera().is_none() => {
                let len = self.session.frame_len();
                if values.len() != len {
                    return Err(Refused(format!("{} values; the file reads frames of {len}", values.len())));
                }
                self.session.push_frame(&values)
            }
            frame => {
                let picture = self.recorded_picture(frame)?;
                self.session.push_camera_frame(&picture.data)
            }
        };
        pushed.map_err(|e| Refused(e.to_string()))
    }

    /// Records a frame of a [`Boundary::Moving`] touch, read as the file says; the touch's answer
    /// once the recording holds `frames`.
    fn record(&mut self, decoded: Decoded, received: Stamp, frames: usize) -> Result<Option<Answer>, Refused> {
        let started = Instant::now();
        self.last_began = started;
        let picture = self.recorded_picture(decoded.frame)?;
        let camera = self.classifier.camera().expect("a moving span's file records a camera");
        let read = picture.clone().read_as(&camera).map_err(Refused)?;
        self.recording.motion.push(&picture);
        self.recording.read.push(read);
        self.last = decoded.stamp.unwrap_or(received);
        self.recording.stamps.push(self.last);
        self.frames += 1;
        self.compute += started.elapsed();
        if self.frames == frames {
            return self.finish_recording("recording").map(Some);
        }
        Ok(None)
    }

    /// The recording's answer: the window's frames taken over its moving span (after its first
    /// frame, the background, where the file subtracts it), pushed and answered.
    fn finish_recording(&mut self, ended_by: &'static str) -> Result<Answer, Refused> {
        let started = Instant::now();
        let recording = std::mem::take(&mut self.recording);
        let window = self.session.frames();
        if recording.read.len() < window {
            let recorded = recording.read.len();
            self.reset();
            return Err(Refused(format!(
                "a recording of {recorded} frames ended by {ended_by}, fewer than the window's {window}: dropped"
            )));
        }
        let taken = recording.motion.take(window);
        let subtract_first = self.classifier.camera().is_some_and(|c| c.subtract_first);
        let first = subtract_first.then_some(0);
        let pushed =
            first.into_iter().chain(taken.frames.iter().copied()).try_for_each(|i| self.session.push_read_camera_frame(&recording.read[i]));
        if let Err(e) = pushed {
            self.reset();
            return Err(Refused(format!("the recording of {} frames: {e}", recording.read.len())));
        }
        self.last = recording.stamps[*taken.frames.last().expect("a window holds a frame")];
        self.compute += started.elapsed();
        self.finish(ended_by)
    }

    /// A camera's frame as it was recorded, of the file's camera's shape.
    fn recorded_picture(&self, frame: Frame) -> Result<Picture, Refused> {
        match (frame, self.classifier.camera()) {
            (Frame::Picture(p), Some(camera)) if camera.recorded == p.shape() => Ok(p),
            (Frame::Picture(p), Some(camera)) => {
                let [h, w, c] = camera.recorded;
                Err(Refused(format!("a frame of {}; the file reads the camera's {h} × {w} × {c}", p.describe())))
            }
            (Frame::Picture(_), None) => Err(Refused("a camera's frame; the file reads a taxel array's values".into())),
            (Frame::Values { .. }, _) => Err(Refused("a taxel array's values; the file reads a camera's frames".into())),
        }
    }

    /// Contact begins (`true`) or ends (`false`): an ending touch is answered from what it has.
    pub fn contact(&mut self, on: bool) -> Result<Option<Answer>, Refused> {
        let was = std::mem::replace(&mut self.in_contact, on);
        if matches!(self.boundary, Boundary::Moving(_)) && !on && was && self.frames > 0 {
            self.last_began = Instant::now();
            return self.finish_recording("contact").map(Some);
        }
        if self.boundary != Boundary::Contact || on || !was || self.session.received() == 0 {
            return Ok(None);
        }
        self.last_began = Instant::now();
        self.finish("contact").map(Some)
    }

    /// The publisher `gid` has left the graph: a touch of its frames is dropped, unanswered,
    /// and said so.
    pub fn publisher_gone(&mut self, gid: [u8; 16]) -> Option<String> {
        if self.frames == 0 || self.source != Some(gid) {
            return None;
        }
        let frames = self.frames;
        self.reset();
        Some(format!("the publisher of the touch's frames left after {frames} frames: the touch is dropped"))
    }

    /// Ends the touch at once, unanswered.
    pub fn reset(&mut self) {
        self.session.reset();
        self.recording = Recording::default();
        self.frames = 0;
        self.compute = Duration::ZERO;
    }

    /// The touch's answer from the frames it has: the whole window's, or the provisional answer
    /// of the temporal tokens it fills.
    fn finish(&mut self, ended_by: &'static str) -> Result<Answer, Refused> {
        let started = Instant::now();
        let prediction = if self.session.received() == self.session.frames() {
            self.session.finish().map(Ok)
        } else {
            self.session.peek().map(|p| Ok(p.prediction))
        };
        let prediction = match prediction {
            Ok(p) => p,
            Err(e) => {
                self.reset();
                Err(Refused(format!("the touch ended after {} frames: {e}", self.frames)))
            }
        }?;
        self.compute += started.elapsed();
        Ok(self.answer(prediction, ended_by))
    }

    /// The answer, the session emptied for the next touch.
    fn answer(&mut self, prediction: Prediction, ended_by: &'static str) -> Answer {
        let status = Status {
            class: prediction.label.clone(),
            frames: self.frames,
            window: self.session.frames(),
            early_stop: ended_by == "early_stop",
            ended_by,
            compute_ms: self.compute.as_secs_f64() * 1e3,
            last_ms: self.last_began.elapsed().as_secs_f64() * 1e3,
        };
        let answer = Answer { prediction, stamp: self.last, status };
        self.reset();
        answer
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn refused(model: &str, boundary: Boundary) -> String {
        let classifier = Classifier::load(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(model)).unwrap();
        Touches::new(classifier, boundary, true).err().expect("refused").to_string()
    }

    #[test]
    fn a_moving_span_is_a_camera_s_and_holds_a_window() {
        assert!(refused("tests/golden/icub20/model.onnx", Boundary::Moving(300)).contains("touch:=moving takes a camera's recording"));
        assert!(refused("shipped/physiclear.onnx", Boundary::Moving(2)).contains("recording:=2: a recording must hold the window's"));
    }
}
