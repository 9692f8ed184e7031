//! [`Session::push_camera_frame`]: a camera's 8-bit frames, as the camera gives them, read as
//! the training's import read its videos ([`crate::picture::Picture::read_as`]).

use crate::picture::Picture;
use crate::{Error, Result, Session};

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
