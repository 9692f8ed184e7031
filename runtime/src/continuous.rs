//! [`Continuous`]: classify a stream longer than the window, as a robot that keeps sliding or
//! explores without a fixed touch length produces it.
//!
//! It keeps the latest window's frames in a ring and, after every `every` temporal tokens once a
//! whole window has arrived, answers for the window that ends at the latest frame: the same
//! batch-1 plan as [`Classifier::classify`] on that window, so the answers are the batch
//! classification's, bit for bit. Each answer costs one whole window's classification (the
//! spatial stage encodes a token with its position in the window, which changes as the window
//! slides, so no encoding carries over); `pvt3-run --bench` measures it per token.

use std::sync::Arc;

use tract_core::prelude::*;

use crate::classifier::prediction;
use crate::error::tract_error;
use crate::plan::Plan;
use crate::{Classifier, Error, Prediction, Result};

/// A stream in progress ([`Classifier::continuous`]). It shares the classifier's plan and may
/// outlive it.
pub struct Continuous {
    plan: Arc<Plan>,
    classes: Vec<String>,
    /// `[1, height, width, (channels,) frames]`
    shape: Vec<usize>,
    frame_len: usize,
    frames: usize,
    /// Frames between answers: `every` temporal tokens.
    stride: usize,
    /// The latest `frames` frames, frame `f` of the stream at `f % frames`.
    ring: Vec<f32>,
    received: u64,
    /// The window in the model's layout, `[values of a frame][frames]`, rebuilt for each answer.
    window: Vec<f32>,
}

impl Classifier {
    /// A continuous classification of an unbounded stream of frames, answering for the latest
    /// window after every `every` temporal tokens (1: after each). Works for every file,
    /// pruned or with a spectral head that reads the whole window too, since it classifies
    /// whole windows.
    pub fn continuous(&self, every: usize) -> Result<Continuous> {
        if every == 0 {
            return Err(Error::NoStride);
        }
        let (sample, frames) = (self.sample_shape(), *self.sample_shape().last().expect("a frame axis"));
        let frame_len = self.frame_len();
        Ok(Continuous {
            plan: self.plan(1)?,
            classes: self.classes().to_vec(),
            shape: std::iter::once(1).chain(sample.iter().copied()).collect(),
            frame_len,
            frames,
            stride: every * self.tubelet(),
            ring: crate::heap::zeros(frames * frame_len, "a window's ring of frames")?,
            received: 0,
            window: crate::heap::zeros(frames * frame_len, "a window")?,
        })
    }
}

impl Continuous {
    /// Values in one frame: `height × width × channels`.
    pub fn frame_len(&self) -> usize {
        self.frame_len
    }

    /// Frames in the window each answer reads.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Frames received since the start or the last [`Continuous::reset`].
    pub fn received(&self) -> u64 {
        self.received
    }

    /// Takes the next frame, `[height, width, (channels)]` in row-major order. Returns the answer
    /// for the window of the latest `frames` frames when one is due: once a whole window has
    /// arrived, and then every `every` tokens.
    pub fn push_frame(&mut self, frame: &[f32]) -> Result<Option<Prediction>> {
        if frame.len() != self.frame_len {
            return Err(Error::FrameLength { got: frame.len(), expected: self.frame_len });
        }
        if let Some((index, value)) = frame.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(Error::NonFinite { index, value: *value });
        }
        let slot = (self.received % self.frames as u64) as usize;
        self.ring[slot * self.frame_len..(slot + 1) * self.frame_len].copy_from_slice(frame);
        self.received += 1;
        let frames = self.frames as u64;
        if self.received < frames || !(self.received - frames).is_multiple_of(self.stride as u64) {
            return Ok(None);
        }
        // The oldest frame of the window sits where the next one will go.
        let oldest = (self.received % frames) as usize;
        for t in 0..self.frames {
            let slot = (oldest + t) % self.frames;
            for (v, value) in self.ring[slot * self.frame_len..(slot + 1) * self.frame_len].iter().enumerate() {
                self.window[v * self.frames + t] = *value;
            }
        }
        let input = Tensor::from_shape(&self.shape, &self.window).map_err(tract_error)?;
        let outputs = self.plan.run(tvec!(input.into()))?;
        Ok(Some(prediction(&self.classes, &self.plan.output(&outputs, 1, self.classes.len())?)))
    }

    /// Forgets the stream: the next answer comes after a whole new window.
    pub fn reset(&mut self) {
        self.received = 0;
    }
}

#[cfg(test)]
mod tests;
