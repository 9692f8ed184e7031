//! [`Session`]: classify a touch frame by frame, as the sensor produces it.
//!
//! The exported graph has two stages joined at a named seam (`token_encodings`): the spatial
//! transformer encodes each temporal token from its own frames alone, and the temporal transformer
//! reads all the encodings. So a session drops a pruned frame on arrival, encodes a kept token as
//! soon as its last frame arrives, and at the end of the touch runs only the temporal stage. Both
//! stages are cut from the one file, so streaming and whole-window classification are the same
//! function.
//!
//! A session also answers before the touch ends ([`Session::peek`]): the temporal stage run over
//! the tokens received so far. The file's key bias (`token_bias`, format 1.1) takes −∞ for every
//! token not yet received, so no temporal attention reads one: the CLS token sees the touch so
//! far, exactly as if the window ended there (the f64 reference's `forward_prefix`).
//!
//! A spectral head reads frames, not encodings: for a file whose head streams (`frame_weights`),
//! the session keeps the kept frames received in a window (zeros elsewhere) and hands it to the
//! temporal stage with the bias, from which the head weighs the frames received. A head over an
//! image's space with its seams (`head_features`) is cut once more: the session computes each kept
//! frame's features as the frame arrives and hands the temporal stage those rows instead, so an
//! answer reads 25 rows of features, not every pixel of the window.

use std::sync::Arc;

use tract_core::prelude::*;

use crate::classifier::prediction;
use crate::error::tract_error;
use crate::stages::{Head, Stages};
use crate::{Classifier, Error, Prediction, Result, Touch, TouchReader};

/// A provisional answer ([`Session::peek`]).
#[derive(Clone, Debug)]
pub struct Peek {
    /// The answer from the frames so far.
    pub prediction: Prediction,
    /// The frames it read: those of the whole temporal tokens received, pruned ones included.
    pub frames: usize,
    /// Whether it meets the file's stopping rule (`pvt3.stop_rule`, calibrated by the trainer):
    /// its top probability reached the rule's and the answers after the tokens just before agree
    /// on its class, so the touch may end here. Always false for a file without a rule.
    pub stop: bool,
}

/// One touch in progress. Push its frames in order with [`Session::push_frame`], then
/// [`Session::finish`]; the session is then ready for the next touch. It shares the classifier's
/// optimised stages and may outlive it.
pub struct Session {
    stages: Arc<Stages>,
    /// Frames received so far in this touch.
    received: usize,
    /// The frames of the kept token being filled, `[tubelet, frame]`.
    token: Vec<f32>,
    /// The encodings of the kept tokens completed so far, `[kept, dim]`.
    encodings: Vec<f32>,
    /// For a streaming spectral head, what its temporal stage reads of the frames so far
    /// (`crate::stages::Head`): the window in the sample layout or each frame's features, of the
    /// kept frames received, zeros elsewhere.
    head: Option<Vec<f32>>,
    /// The class answered after each number of tokens of this touch, where one was asked: what
    /// the stopping rule's agreement reads.
    answered: Vec<Option<usize>>,
    /// For a session made for a touch ([`Classifier::session_for`]): its recorded frames, read as
    /// the model reads touches, and the frames read not yet taken.
    reader: Option<(TouchReader, Vec<f32>)>,
    /// For a model of camera frames read less the touch's first (`pvt3.camera`), that frame as
    /// read, once the touch's first camera frame has arrived ([`Session::push_camera_frame`]).
    background: Option<Vec<f32>>,
}

impl Classifier {
    /// A streaming session (builds the two stages on first use).
    pub fn session(&self) -> Result<Session> {
        let stages = self.stages()?;
        let head = stages.head.as_ref().map(|h| crate::heap::zeros(h.shape().iter().product(), "the spectral head's rows")).transpose()?;
        Ok(Session {
            stages,
            received: 0,
            token: Vec::new(),
            encodings: Vec::new(),
            head,
            answered: Vec::new(),
            reader: None,
            background: None,
        })
    }

    /// A streaming session for touches the robot records at `touch` (the speed and force it
    /// commands): it takes the frames as recorded and reads them as the model reads touches
    /// ([`Classifier::read_touch`]), frame by frame ([`TouchReader`]), so that its answers are
    /// those of a session given the frames `read_touch` returns. A model without a reading takes
    /// the frames as they are.
    pub fn session_for(&self, touch: Touch) -> Result<Session> {
        let mut session = self.session()?;
        if let Some(reading) = self.reading() {
            let frame_len = session.frame_len();
            session.reader = Some((TouchReader::new(frame_len, &reading, touch)?, Vec::new()));
        }
        Ok(session)
    }
}

impl Session {
    /// Frames per touch, pruned ones included.
    pub fn frames(&self) -> usize {
        self.stages.kept_index.len() * self.stages.tubelet()
    }

    /// Values in one frame: `height × width × channels`.
    pub fn frame_len(&self) -> usize {
        self.stages.token_shape[2..].iter().product()
    }

    /// Takes the next frame, `[height, width, (channels)]` in row-major order. A frame the model
    /// pruned is dropped at once; the last frame of a kept token runs the spatial stage. A
    /// session for a touch ([`Classifier::session_for`]) takes the frame as recorded and goes on
    /// with the frames it completes, read as the model reads touches.
    pub fn push_frame(&mut self, frame: &[f32]) -> Result<()> {
        let frames = self.frames();
        let full = self.received == frames;
        let Some((reader, read)) = &mut self.reader else { return self.push_read(frame) };
        if full {
            return Err(Error::TooManyFrames { frames });
        }
        reader.push(frame, read)?;
        self.take_read()
    }

    /// Pushes the frames the reader gave out, up to the window's end: frames read beyond it are
    /// not the model's.
    fn take_read(&mut self) -> Result<()> {
        let room = (self.frames() - self.received) * self.frame_len();
        let Some((_, read)) = &mut self.reader else { return Ok(()) };
        let mut read = std::mem::take(read);
        read.truncate(room);
        let result = read.chunks(self.frame_len()).try_for_each(|frame| self.push_read(frame));
        if let Some((_, buffer)) = &mut self.reader {
            // The allocation kept for the next frames.
            *buffer = read;
            buffer.clear();
        }
        result
    }

    /// Takes the next frame the model reads.
    fn push_read(&mut self, frame: &[f32]) -> Result<()> {
        let (expected, frames) = (self.frame_len(), self.frames());
        if frame.len() != expected {
            return Err(Error::FrameLength { got: frame.len(), expected });
        }
        if self.received == frames {
            return Err(Error::TooManyFrames { frames });
        }
        let tubelet = self.stages.tubelet();
        let Some(kk) = self.stages.kept_index[self.received / tubelet] else {
            self.received += 1;
            return Ok(());
        };
        if let Some((index, value)) = frame.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(Error::NonFinite { index, value: *value });
        }
        self.token.extend_from_slice(frame);
        self.head_takes(frame)?;
        self.received += 1;
        if self.received.is_multiple_of(tubelet) {
            let frames = Tensor::from_shape(&self.stages.token_shape, &self.token).map_err(tract_error)?;
            let index = Tensor::from_shape(&[1], &[kk as i64]).map_err(tract_error)?;
            let out = self.stages.spatial.run(tvec!(frames.into(), index.into()))?;
            self.encodings.extend(self.stages.spatial.output(&out, 0, self.stages.dim)?);
            self.token.clear();
        }
        Ok(())
    }

    /// The streaming spectral head's part of the next frame, a kept one: written into the window,
    /// or its features computed.
    fn head_takes(&mut self, frame: &[f32]) -> Result<()> {
        let (Some(head), Some(so_far)) = (&self.stages.head, &mut self.head) else { return Ok(()) };
        let n = self.received;
        match head {
            // The sample layout is frame-last: value `p` of frame `n` sits at `p · frames + n`.
            Head::Window(shape) => {
                let frames = *shape.last().expect("a window has a frame axis");
                so_far.iter_mut().skip(n).step_by(frames).zip(frame).for_each(|(w, v)| *w = *v);
            }
            Head::Features { plan, shape } => {
                let row: usize = shape[1..].iter().product();
                let frame_shape = [&[1], &self.stages.token_shape[2..]].concat();
                let frame = Tensor::from_shape(&frame_shape, frame).map_err(tract_error)?;
                let out = plan.run(tvec!(frame.into()))?;
                so_far[n * row..(n + 1) * row].copy_from_slice(&plan.output(&out, 0, row)?);
            }
        }
        Ok(())
    }

    /// Frames received so far in this touch.
    pub fn received(&self) -> usize {
        self.received
    }

    /// The answer for the touch, once all its frames have arrived: runs the temporal stage only.
    /// The session is then empty, ready for the next touch. A session for a touch first takes the
    /// frames read after its last recorded one, as many as the window still lacks; if they are
    /// still too few ([`Error::Incomplete`]) the recorded touch has ended all the same: reset.
    pub fn finish(&mut self) -> Result<Prediction> {
        let frames = self.frames();
        if let Some((reader, read)) = &mut self.reader {
            reader.finish(read);
            self.take_read()?;
        }
        if self.received < frames {
            return Err(Error::Incomplete { got: self.received, frames });
        }
        let prediction = self.temporal(self.stages.kept_index.len())?;
        self.reset();
        Ok(prediction)
    }

    /// A provisional answer from the touch so far, which goes on: the temporal stage over the
    /// temporal tokens whose frames have all arrived (a pruned token as its constant), as if the
    /// touch ended there. With every frame in, it is what [`Session::finish`] answers.
    /// [`Error::NoTokenYet`] before the first token is complete; [`Error::NoPrefixes`] for a file
    /// exported before format 1.1. The stopping rule reads the answers after the tokens just
    /// before too, until one differs: those not asked for are computed here (a session that peeks
    /// after every token runs one temporal stage per peek).
    pub fn peek(&mut self) -> Result<Peek> {
        if !self.stages.prefixes {
            return Err(Error::NoPrefixes);
        }
        let tokens = self.received / self.stages.tubelet();
        if tokens == 0 {
            return Err(Error::NoTokenYet { tubelet: self.stages.tubelet() });
        }
        let prediction = self.temporal(tokens)?;
        self.remember(tokens, prediction.class);
        let stop = match self.stages.stop_rule {
            Some(rule) => rule.stops(tokens, prediction.class, prediction.probabilities[prediction.class], |j| self.class_after(j))?,
            None => false,
        };
        Ok(Peek { prediction, frames: tokens * self.stages.tubelet(), stop })
    }

    /// The class answered after the first `tokens` tokens of this touch (all received).
    fn class_after(&mut self, tokens: usize) -> Result<usize> {
        if let Some(Some(class)) = self.answered.get(tokens) {
            return Ok(*class);
        }
        let class = self.temporal(tokens)?.class;
        self.remember(tokens, class);
        Ok(class)
    }

    fn remember(&mut self, tokens: usize, class: usize) {
        if self.answered.len() <= tokens {
            self.answered.resize(tokens + 1, None);
        }
        self.answered[tokens] = Some(class);
    }

    /// The temporal stage over the first `tokens` temporal tokens, all of them received: the kept
    /// ones' encodings so far, zeros for the rest, whose keys the bias hides.
    fn temporal(&self, tokens: usize) -> Result<Prediction> {
        let (dim, total) = (self.stages.dim, self.stages.kept_index.len());
        let kept = self.stages.kept_index.iter().flatten().count();
        // One copy of the encodings, as finishing made before provisional answers existed.
        let mut encodings = Vec::with_capacity(kept * dim);
        encodings.extend_from_slice(&self.encodings);
        encodings.resize(kept * dim, 0.0);
        let encodings = tract_ndarray::Array2::from_shape_vec((kept, dim), encodings).map_err(tract_error)?;
        let mut inputs = tvec!(Tensor::from(encodings).into());
        if self.stages.prefixes {
            let bias: Vec<f32> = (0..=total).map(|k| if k <= tokens { 0.0 } else { f32::NEG_INFINITY }).collect();
            inputs.push(Tensor::from_shape(&[1, 1, 1, total + 1], &bias).map_err(tract_error)?.into());
        }
        if let (Some(head), Some(so_far)) = (&self.stages.head, &self.head) {
            inputs.push(Tensor::from_shape(head.shape(), so_far).map_err(tract_error)?.into());
        }
        let out = self.stages.temporal.run(inputs)?;
        Ok(prediction(&self.stages.classes, &self.stages.temporal.output(&out, 0, self.stages.classes.len())?))
    }

    /// Forgets the touch in progress.
    pub fn reset(&mut self) {
        if let Some((reader, read)) = &mut self.reader {
            reader.reset();
            read.clear();
        }
        self.received = 0;
        self.token.clear();
        self.encodings.clear();
        if let Some(so_far) = &mut self.head {
            so_far.fill(0.0);
        }
        self.answered.clear();
        self.background = None;
    }
}

mod camera;
#[cfg(test)]
mod tests;
