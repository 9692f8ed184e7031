//! [`Session`]: classify a touch frame by frame, as the sensor produces it.
//!
//! The exported graph has two stages joined at a named seam (`token_encodings`): the spatial
//! transformer encodes each temporal token from its own frames alone, and the temporal transformer
//! reads all the encodings. So a session drops a pruned frame on arrival, encodes a kept token as
//! soon as its last frame arrives, and at the end of the touch runs only the temporal stage. Both
//! stages are cut from the one file, so streaming and whole-window classification are the same
//! function.

use std::sync::Arc;

use pvt3_format::{PROBABILITIES, TOKEN_ENCODINGS, TOKEN_FRAMES, TOKEN_INDEX};
use tract_core::prelude::*;

use crate::classifier::prediction;
use crate::error::tract_error;
use crate::plan::{outputs_of, Plan};
use crate::{Classifier, Error, Prediction, Result};

/// The two stages of a classifier, each optimised for its streaming shape.
pub(crate) struct Stages {
    /// One kept token's frames `[1, tubelet, height, width, channels]` and its index → `[1, dim]`.
    spatial: Plan,
    /// All kept tokens' encodings `[kept, dim]` → probabilities `[1, classes]`.
    temporal: Plan,
    /// For each temporal token, its index among the kept tokens.
    kept_index: Vec<Option<usize>>,
    /// `[1, tubelet, height, width, channels]`
    token_shape: Vec<usize>,
    dim: usize,
    classes: Vec<String>,
}

impl Stages {
    pub(crate) fn new(c: &Classifier) -> Result<Self> {
        let frames = *c.sample_shape().last().expect("a sample has a frame axis");
        let tubelet = c.tubelet();
        let mut kept_index = vec![None; frames / tubelet];
        for (kk, f) in c.kept_frames().iter().step_by(tubelet).enumerate() {
            kept_index[f / tubelet] = Some(kk);
        }
        let kept = c.kept_frames().len() / tubelet;
        let frame = &c.sample_shape()[..c.sample_shape().len() - 1];
        let token_shape = vec![1, tubelet, frame[0], frame[1], frame.get(2).copied().unwrap_or(1)];
        let spatial = [(TOKEN_FRAMES, f32::fact(&token_shape)), (TOKEN_INDEX, i64::fact([1]))];
        Ok(Self {
            spatial: c.optimise(c.wire(&spatial, &[TOKEN_ENCODINGS])?)?,
            temporal: c.optimise(c.wire(&[(TOKEN_ENCODINGS, f32::fact([kept, c.dim()]))], &[PROBABILITIES])?)?,
            kept_index,
            token_shape,
            dim: c.dim(),
            classes: c.classes().to_vec(),
        })
    }
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
}

impl Classifier {
    /// A streaming session (builds the two stages on first use).
    pub fn session(&self) -> Result<Session> {
        Ok(Session { stages: self.stages()?, received: 0, token: Vec::new(), encodings: Vec::new() })
    }
}

impl Stages {
    /// Frames per temporal token.
    fn tubelet(&self) -> usize {
        self.token_shape[1]
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
    /// pruned is dropped at once; the last frame of a kept token runs the spatial stage.
    pub fn push_frame(&mut self, frame: &[f32]) -> Result<()> {
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
        self.received += 1;
        if self.received.is_multiple_of(tubelet) {
            let frames = Tensor::from_shape(&self.stages.token_shape, &self.token).map_err(tract_error)?;
            let index = Tensor::from_shape(&[1], &[kk as i64]).map_err(tract_error)?;
            let out = self.stages.spatial.run(tvec!(frames.into(), index.into()))?;
            self.encodings.extend(outputs_of(&out, 0, self.stages.dim)?);
            self.token.clear();
        }
        Ok(())
    }

    /// Frames received so far in this touch.
    pub fn received(&self) -> usize {
        self.received
    }

    /// The answer for the touch, once all its frames have arrived: runs the temporal stage only.
    /// The session is then empty, ready for the next touch.
    pub fn finish(&mut self) -> Result<Prediction> {
        let frames = self.frames();
        if self.received < frames {
            return Err(Error::Incomplete { got: self.received, frames });
        }
        let dim = self.stages.dim;
        let encodings = Tensor::from_shape(&[self.encodings.len() / dim, dim], &self.encodings).map_err(tract_error)?;
        let out = self.stages.temporal.run(tvec!(encodings.into()))?;
        let probabilities = outputs_of(&out, 0, self.stages.classes.len())?;
        self.reset();
        Ok(prediction(&self.stages.classes, &probabilities))
    }

    /// Forgets the touch in progress.
    pub fn reset(&mut self) {
        self.received = 0;
        self.token.clear();
        self.encodings.clear();
    }
}

#[cfg(test)]
mod tests;
