//! [`Camera`]: how a camera-based sensor's frames (GelSight, DIGIT) became the frames a model
//! was trained on, written into the exported file ([`crate::keys::CAMERA`]) so that a robot hands
//! the runtime its camera's 8-bit frames as they come and gets them read as `pvt3 import` read
//! the training's: cropped, shrunk by area averaging, greyed, less the touch's first frame.

use serde::{Deserialize, Serialize};

use crate::Dims;

/// A rectangle of a frame: its top-left pixel and its size.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Crop {
    /// The first row taken.
    pub top: usize,
    /// The first column taken.
    pub left: usize,
    /// Rows taken.
    pub height: usize,
    /// Columns taken.
    pub width: usize,
}

impl std::str::FromStr for Crop {
    type Err = String;

    /// `HEIGHTxWIDTH+TOP+LEFT`, e.g. `200x280+20+20` (as ImageMagick writes a geometry).
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("`{s}`: expected HEIGHTxWIDTH+TOP+LEFT, e.g. 200x280+20+20");
        let number = |v: &str| v.trim().parse::<usize>().map_err(|_| bad());
        let mut parts = s.split('+');
        let (h, w) = parts.next().and_then(|size| size.split_once(['x', 'X', '×'])).ok_or_else(bad)?;
        let (top, left) = (number(parts.next().ok_or_else(bad)?)?, number(parts.next().ok_or_else(bad)?)?);
        let (height, width) = (number(h)?, number(w)?);
        if parts.next().is_some() || height == 0 || width == 0 {
            return Err(bad());
        }
        Ok(Self { top, left, height, width })
    }
}

impl Crop {
    /// Whether the crop lies within a frame of `height` × `width`, or why not: the one check of
    /// a crop, for a file's camera and a frame alike.
    pub fn fits(&self, height: usize, width: usize) -> Result<(), String> {
        if self.top.saturating_add(self.height) > height || self.left.saturating_add(self.width) > width {
            return Err(format!("the crop {self} does not fit in a frame of {height} × {width}"));
        }
        Ok(())
    }
}

/// `size` (`[height, width]`), where frames of `height` × `width` can be shrunk to it by area
/// averaging, or why not: the one check of a size, for a file's camera and a frame alike.
pub(crate) fn shrinking(size: [usize; 2], height: usize, width: usize) -> Result<[usize; 2], String> {
    let [h, w] = size;
    if h == 0 || w == 0 || h > height || w > width {
        return Err(format!("the size {h} × {w} is not a shrinking of {height} × {width} (area averaging only shrinks)"));
    }
    Ok(size)
}

impl std::fmt::Display for Crop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}x{}+{}+{}", self.height, self.width, self.top, self.left)
    }
}

/// How a camera's frames were read: `recorded` as the camera gives them, then `crop`, `size`
/// and `grey` in that order; with `subtract_first`, the frames minus the touch's first frame
/// (the gel before contact), which is not itself one of the model's frames.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Camera {
    /// A frame as the camera gives it: `[height, width, channels]` (3: RGB, 1: grey).
    pub recorded: [usize; 3],
    /// The part of each frame kept (`pvt3 import --crop`); `None`: the whole frame.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub crop: Option<Crop>,
    /// `[height, width]` after area averaging.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size: Option<[usize; 2]>,
    /// Colours averaged to one grey channel (`pvt3 import --grey`).
    #[serde(default)]
    pub grey: bool,
    /// Each frame read less the touch's first (`pvt3 import --subtract-first`), which is not
    /// itself one of the model's frames.
    #[serde(default)]
    pub subtract_first: bool,
}

impl Camera {
    /// A frame as the model reads it, `[height, width, channels]`.
    pub fn read_shape(&self) -> [usize; 3] {
        let [mut h, mut w, c] = self.recorded;
        if let Some(crop) = self.crop {
            (h, w) = (crop.height, crop.width);
        }
        if let Some([sh, sw]) = self.size {
            (h, w) = (sh, sw);
        }
        [h, w, if self.grey { 1 } else { c }]
    }

    /// Why frames read so cannot be a model's of `dims`, if they cannot: a crop outside the
    /// recorded frame, a size larger than the crop (area averaging only shrinks), or a shape that
    /// is not the model's input.
    pub fn problem(&self, dims: &Dims) -> Option<String> {
        let [h, w, c] = self.recorded;
        if h == 0 || w == 0 || !(c == 1 || c == 3) {
            return Some(format!("recorded frames of {h} × {w} × {c}: expected a height, a width and 1 or 3 channels"));
        }
        if let Some(Err(why)) = self.crop.map(|k| k.fits(h, w)) {
            return Some(why);
        }
        let (ch, cw) = self.crop.map_or((h, w), |k| (k.height, k.width));
        if let Some(Err(why)) = self.size.map(|size| shrinking(size, ch, cw)) {
            return Some(why);
        }
        let read = self.read_shape();
        (read != [dims.height, dims.width, dims.channels])
            .then(|| format!("reads frames of {read:?}, but the model's are {:?}", [dims.height, dims.width, dims.channels]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crops_parse_as_geometries() {
        let c: Crop = "2x3+1+2".parse().unwrap();
        assert_eq!(c, Crop { top: 1, left: 2, height: 2, width: 3 });
        assert_eq!(c.to_string(), "2x3+1+2");
        for bad in ["2x3", "2x3+1", "0x3+1+1", "2x3+1+1+1", "axb+1+1"] {
            assert!(bad.parse::<Crop>().unwrap_err().contains("HEIGHTxWIDTH+TOP+LEFT"), "{bad}");
        }
    }

    #[test]
    fn a_camera_reads_the_model_s_frames_or_says_why_not() {
        let dims = Dims { height: 30, width: 40, channels: 1, frames: 25, tubelet: 1, dim: 64 };
        let crop = Some(Crop { top: 0, left: 40, height: 240, width: 240 });
        let camera = Camera { recorded: [240, 320, 3], crop, size: Some([30, 40]), grey: true, subtract_first: true };
        assert_eq!(camera.read_shape(), [30, 40, 1]);
        assert_eq!(camera.problem(&dims), None);
        let json = serde_json::to_string(&camera).unwrap();
        assert_eq!(serde_json::from_str::<Camera>(&json).unwrap(), camera);
        let problems = [
            (Camera { grey: false, ..camera }, "reads frames of [30, 40, 3], but the model's are [30, 40, 1]"),
            (Camera { recorded: [200, 320, 3], ..camera }, "does not fit in a frame of 200 × 320"),
            (Camera { size: Some([300, 40]), ..camera }, "the size 300 × 40 is not a shrinking of 240 × 240"),
            (Camera { recorded: [240, 320, 2], ..camera }, "expected a height, a width and 1 or 3 channels"),
        ];
        for (c, expected) in problems {
            let got = c.problem(&dims).unwrap();
            assert!(got.contains(expected), "{got}");
        }
    }
}
