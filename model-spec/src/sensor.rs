//! The kind of sensor a data set's frames come from, recorded by `pvt3 import` (which knows what
//! it read: a CSV's or a multi-array's taxels, a camera's frames) and read by every choice that
//! differs between kinds: the layout derived for a sensor no preset fits
//! ([`crate::Config::for_sensor`], by [`Sensor::reads_images`]), whether `--robust` adds a spectral
//! head over each channel's frames, and what the trainer says of the layout. A set that does not
//! record it (written by hand, or before the import recorded it) is taken by its frames' size
//! ([`Sensor::of`]). A new kind is a variant here with its rule, its layout in `for_sensor`, and
//! its import (docs/architecture.md, "Adding a sensor kind").

/// The kind of sensor whose frames a data set holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Sensor {
    /// A tactile array's taxels or electrodes: a few values a frame on a small grid, or none
    /// (iCub skin, BioTac, a CSV folder's channels).
    Array,
    /// A camera-based sensor's images (GelSight, DIGIT, TacTip).
    Camera,
}

/// The least height and width, in values, of a frame that is an image (a camera's): smaller grids
/// are a tactile array's taxels or electrodes.
pub const IMAGE_SIDE: usize = 16;

impl Sensor {
    /// Its name as a data set records it: `array` or `camera`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Array => "array",
            Self::Camera => "camera",
        }
    }

    /// The kind a data set records by [`Sensor::name`]; `None` for another word.
    pub fn from_name(name: &str) -> Option<Self> {
        [Self::Array, Self::Camera].into_iter().find(|s| s.name() == name)
    }

    /// The kind of sensor whose samples are `[height, width, (channels,) frames]`: a camera's
    /// where a frame is an image, at least [`IMAGE_SIDE`] values each way; an array's otherwise.
    /// For a set that does not record its kind: a large taxel grid passes for a camera here, and
    /// is read as an image either way ([`Sensor::reads_images`]).
    pub fn of(sample_shape: &[usize]) -> Self {
        match *sample_shape {
            [height, width, ..] if is_image(height, width) => Self::Camera,
            _ => Self::Array,
        }
    }

    /// Whether a layout derived for this sensor's frames of `height` × `width` reads them as
    /// images (patches, and a spectral head over the image's space) rather than as channels (a
    /// token of every value). A camera's frames are images. So is a tactile array's grid of at
    /// least [`IMAGE_SIDE`] taxels each way: on two synthetic 32 × 32 sets, a texture sliding and
    /// a shape pressed, validation read better with the image's layout than with the channels'
    /// (docs/results.md, "A large taxel grid").
    pub fn reads_images(self, height: usize, width: usize) -> bool {
        match self {
            Self::Camera => true,
            Self::Array => is_image(height, width),
        }
    }
}

/// Whether a frame of `height` × `width` values is an image: at least [`IMAGE_SIDE`] each way.
fn is_image(height: usize, width: usize) -> bool {
    height >= IMAGE_SIDE && width >= IMAGE_SIDE
}

impl std::fmt::Display for Sensor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Array => "a tactile array",
            Self::Camera => "a camera",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_frame_is_a_camera_s_image_from_sixteen_values_each_way() {
        assert_eq!(Sensor::of(&[6, 10, 75]), Sensor::Array);
        assert_eq!(Sensor::of(&[19, 1, 400]), Sensor::Array);
        assert_eq!(Sensor::of(&[15, 40, 3, 25]), Sensor::Array);
        assert_eq!(Sensor::of(&[16, 16, 1]), Sensor::Camera);
        assert_eq!(Sensor::of(&[30, 40, 3, 25]), Sensor::Camera);
        assert_eq!(Sensor::of(&[10]), Sensor::Array);
        for s in [Sensor::Array, Sensor::Camera] {
            assert_eq!(Sensor::from_name(s.name()), Some(s));
        }
        assert_eq!(Sensor::from_name("grid"), None);
    }

    #[test]
    fn a_camera_s_frames_and_a_large_taxel_grid_read_as_images() {
        assert!(Sensor::Camera.reads_images(12, 12) && Sensor::Camera.reads_images(240, 320));
        assert!(Sensor::Array.reads_images(16, 16) && Sensor::Array.reads_images(32, 32));
        assert!(!Sensor::Array.reads_images(6, 10) && !Sensor::Array.reads_images(19, 1) && !Sensor::Array.reads_images(15, 40));
    }
}
