//! [`Session::push_camera_frame`]: a camera's 8-bit frames, as the camera gives them, read as
//! the training's import read its videos ([`crate::Picture::read_as`]); and
//! [`Classifier::classify_camera_touches`], whole touches of them (`pvt3-run`).

use crate::{Classifier, Error, Picture, Prediction, Result, Session};

impl Classifier {
    /// The answers for `batch` touches of a camera's 8-bit frames as it gives them, laid out as a
    /// data set holds touches, frames last: `[batch, height, width, channels, frames]` of the
    /// camera's frame ([`Classifier::camera_frame_len`] values a frame), each touch's frames
    /// pushed in order to a session ([`Session::push_camera_frame`]) and answered at its end. A
    /// model read less the touch's first frame takes that frame first, one more than its window.
    pub fn classify_camera_touches(&self, values: &[u8], batch: usize) -> Result<Vec<Prediction>> {
        let frame_len = self.camera_frame_len();
        if batch == 0 {
            return Err(Error::EmptyBatch);
        }
        let touch_len = values.len() / batch;
        if touch_len * batch != values.len() || !touch_len.is_multiple_of(frame_len) || touch_len == 0 {
            let got = values.len();
            return Err(Error::Touch(format!("{got} bytes are not {batch} touches of whole camera frames of {frame_len} bytes")));
        }
        let frames = touch_len / frame_len;
        let mut session = self.session()?;
        let mut frame = crate::heap::zeros(frame_len, "a camera's frame")?;
        values
            .chunks_exact(touch_len)
            .map(|touch| {
                for t in 0..frames {
                    frame.iter_mut().enumerate().for_each(|(i, v)| *v = touch[i * frames + t]);
                    session.push_camera_frame(&frame)?;
                }
                session.finish()
            })
            .collect()
    }
}

impl Session {
    /// Takes the camera's next frame, 8-bit, `[height, width, channels]` row-major, channels
    /// innermost. A model whose file says how its frames were read from a camera's
    /// ([`crate::Classifier::camera`]) gets it cropped, shrunk and greyed as `pvt3 import` read
    /// the training's, and, if it was trained on frames less the touch's first, the first frame
    /// of each touch is that background and none of the model's frames. A model without takes
    /// the bytes as its own frame. Then as [`Session::push_frame`].
    pub fn push_camera_frame(&mut self, frame: &[u8]) -> Result<()> {
        let Some(camera) = self.stages.camera else {
            return self.push_frame(&frame.iter().map(|v| f32::from(*v)).collect::<Vec<_>>());
        };
        let [height, width, channels] = camera.recorded;
        if frame.len() != height * width * channels {
            return Err(Error::FrameLength { got: frame.len(), expected: height * width * channels });
        }
        let picture = Picture { height, width, channels, data: frame.to_vec() }.read_as(&camera).map_err(Error::Touch)?;
        self.push_read_camera_frame(&picture)
    }

    /// Takes a camera's frame already read as the file says ([`Picture::read_as`] with its
    /// [`crate::Classifier::camera`]), for a caller that keeps read frames until it knows which a
    /// touch takes (a recording's moving span): the background, the first frame of each touch of a
    /// model trained less it, or the model's next frame, as [`Session::push_camera_frame`].
    pub fn push_read_camera_frame(&mut self, picture: &Picture) -> Result<()> {
        let Some(camera) = self.stages.camera else {
            return Err(Error::Touch("a camera's frame read as the file says, but the file records no camera".into()));
        };
        if picture.data.len() != self.frame_len() {
            return Err(Error::FrameLength { got: picture.data.len(), expected: self.frame_len() });
        }
        let values = picture.data.iter().map(|v| f32::from(*v));
        let frame: Vec<f32> = match (&self.background, camera.subtract_first) {
            (_, false) => values.collect(),
            (None, true) => {
                self.background = Some(values.collect());
                return Ok(());
            }
            (Some(background), true) => values.zip(background).map(|(v, b)| v - b).collect(),
        };
        self.push_frame(&frame)
    }
}
