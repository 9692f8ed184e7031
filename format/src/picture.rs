//! A camera frame as the camera gives it (8-bit, rows × columns × RGB), and what `pvt3 import`
//! does to one: crop, shrink by area averaging, grey ([`Picture::read_as`] a [`Camera`] says).
//! Kept in u8 from file to data set: a GelSight data set is a few gigabytes as u8 and four times
//! that as f32. The import and a robot's session (the runtime's `Session::push_camera_frame`)
//! read frames with this one code.

use crate::camera::shrinking;
use crate::{Camera, Crop};

/// One frame: `height × width × channels` bytes, row-major, channels innermost (1: grey, 3: RGB).
#[derive(Clone, Debug, PartialEq)]
pub struct Picture {
    /// Rows.
    pub height: usize,
    /// Columns.
    pub width: usize,
    /// Values a pixel (1: grey, 3: RGB).
    pub channels: usize,
    /// The `height × width × channels` bytes.
    pub data: Vec<u8>,
}

impl Picture {
    /// `[height, width, channels]`.
    pub fn shape(&self) -> [usize; 3] {
        [self.height, self.width, self.channels]
    }

    /// Its size and colour, for errors: `240 × 320 RGB`.
    pub fn describe(&self) -> String {
        format!("{} × {} {}", self.height, self.width, if self.channels == 1 { "grey" } else { "RGB" })
    }

    /// The frame read as `camera` reads the camera's frames: cropped, shrunk, greyed; or why it
    /// cannot be (a crop that does not fit, a size larger than the crop).
    pub fn read_as(self, camera: &Camera) -> Result<Self, String> {
        let p = match camera.crop {
            Some(c) => self.crop(c)?,
            None => self,
        };
        let p = match camera.size {
            Some(size) => {
                let [h, w] = shrinking(size, p.height, p.width)?;
                p.resize(h, w)
            }
            None => p,
        };
        Ok(if camera.grey { p.grey() } else { p })
    }

    /// The rectangle `c`, or why it does not fit in this frame.
    pub fn crop(&self, c: Crop) -> Result<Self, String> {
        c.fits(self.height, self.width)?;
        let row = self.width * self.channels;
        let data = (c.top..c.top + c.height)
            .flat_map(|y| &self.data[y * row + c.left * self.channels..y * row + (c.left + c.width) * self.channels])
            .copied()
            .collect();
        Ok(Self { height: c.height, width: c.width, data, ..*self })
    }

    /// Shrunk (or kept) to `height × width` by area averaging: each new pixel is the mean of the
    /// old pixels it covers, weighted by how much of each it covers, rounded.
    pub fn resize(&self, height: usize, width: usize) -> Self {
        if (height, width) == (self.height, self.width) {
            return self.clone();
        }
        let (rows, cols) = (area_weights(self.height, height), area_weights(self.width, width));
        let c = self.channels;
        // Columns first, in f32: [self.height][width][c].
        let mut narrow = vec![0f32; self.height * width * c];
        for y in 0..self.height {
            for (x, weights) in cols.iter().enumerate() {
                for &(from, w) in weights {
                    for k in 0..c {
                        narrow[(y * width + x) * c + k] += w * f32::from(self.data[(y * self.width + from) * c + k]);
                    }
                }
            }
        }
        let mut data = vec![0u8; height * width * c];
        for (y, weights) in rows.iter().enumerate() {
            for i in 0..width * c {
                let v: f32 = weights.iter().map(|&(from, w)| w * narrow[from * width * c + i]).sum();
                data[y * width * c + i] = v.round().clamp(0.0, 255.0) as u8;
            }
        }
        Self { height, width, channels: c, data }
    }

    /// One grey channel (ITU-R BT.601 luma, as OpenCV's `COLOR_RGB2GRAY`), rounded; a grey frame
    /// is kept.
    pub fn grey(&self) -> Self {
        if self.channels == 1 {
            return self.clone();
        }
        let data = self
            .data
            .chunks_exact(self.channels)
            .map(|p| (0.299 * f32::from(p[0]) + 0.587 * f32::from(p[1]) + 0.114 * f32::from(p[2])).round() as u8)
            .collect();
        Self { channels: 1, data, ..*self }
    }
}

/// For each of `to` cells along an axis of `from` pixels, the pixels it covers and their weights
/// (the share of the cell each covers; they sum to 1).
fn area_weights(from: usize, to: usize) -> Vec<Vec<(usize, f32)>> {
    let scale = from as f64 / to as f64;
    (0..to)
        .map(|i| {
            let (start, end) = (i as f64 * scale, (i + 1) as f64 * scale);
            (start.floor() as usize..(end.ceil() as usize).min(from))
                .map(|j| (j, ((end.min(j as f64 + 1.0) - start.max(j as f64)) / scale) as f32))
                .filter(|&(_, w)| w > 0.0)
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn picture(height: usize, width: usize, channels: usize) -> Picture {
        let data = (0..height * width * channels).map(|i| (i * 7 % 256) as u8).collect();
        Picture { height, width, channels, data }
    }

    #[test]
    fn a_crop_cuts_the_rectangle() {
        let c: Crop = "2x3+1+2".parse().unwrap();
        let p = picture(4, 6, 3);
        let cut = p.crop(c).unwrap();
        assert_eq!((cut.height, cut.width, cut.data.len()), (2, 3, 18));
        assert_eq!(cut.data[..3], p.data[(6 + 2) * 3..(6 + 2) * 3 + 3]);
        assert_eq!(cut.data[9..12], p.data[(2 * 6 + 2) * 3..(2 * 6 + 2) * 3 + 3]);
        assert!(p.crop("4x6+1+0".parse().unwrap()).unwrap_err().contains("does not fit in a frame of 4 × 6"));
        let huge = format!("{}x1+1+0", usize::MAX);
        assert!(p.crop(huge.parse().unwrap()).unwrap_err().contains("does not fit"));
    }

    #[test]
    fn shrinking_averages_the_area_each_pixel_covers() {
        // Halving averages 2 × 2 blocks.
        let p = Picture { height: 2, width: 4, channels: 1, data: vec![0, 10, 20, 40, 100, 110, 220, 200] };
        assert_eq!(p.resize(1, 2).data, [55, 120]);
        // Three pixels into two: the middle one counted half in each.
        let q = Picture { height: 1, width: 3, channels: 1, data: vec![0, 90, 30] };
        assert_eq!(q.resize(1, 2).data, [30, 50]);
        // Each channel on its own; an unchanged size is the frame itself.
        let rgb = picture(6, 8, 3);
        let small = rgb.resize(3, 4);
        let r = |y: usize, x: usize| f32::from(rgb.data[(y * 8 + x) * 3]);
        assert_eq!(small.data[0], ((r(0, 0) + r(0, 1) + r(1, 0) + r(1, 1)) / 4.0).round() as u8);
        assert_eq!(rgb.resize(6, 8), rgb);
        // A constant frame stays constant at any size.
        let flat = Picture { height: 7, width: 9, channels: 1, data: vec![77; 63] };
        assert!(flat.resize(3, 4).data.iter().all(|v| *v == 77));
    }

    #[test]
    fn grey_is_the_luma_of_each_pixel() {
        let p = Picture { height: 1, width: 3, channels: 3, data: vec![255, 0, 0, 0, 255, 0, 10, 20, 30] };
        assert_eq!(p.grey().data, [76, 150, 18]);
        assert_eq!(p.grey().grey(), p.grey());
    }

    #[test]
    fn a_camera_crops_then_shrinks_then_greys() {
        let p = picture(8, 12, 3);
        let crop = Crop { top: 2, left: 4, height: 6, width: 8 };
        let camera = Camera { recorded: [8, 12, 3], crop: Some(crop), size: Some([3, 4]), grey: true, subtract_first: false };
        assert_eq!(p.clone().read_as(&camera).unwrap(), p.crop(crop).unwrap().resize(3, 4).grey());
        let larger = Camera { size: Some([7, 4]), ..camera };
        assert!(p.read_as(&larger).unwrap_err().contains("the size 7 × 4 is not a shrinking of 6 × 8"));
    }
}
