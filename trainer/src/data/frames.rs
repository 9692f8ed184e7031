//! Frames: a data set's values as its file holds them. A tactile array's are f32; a camera's
//! stay 8-bit, a quarter of their f32 size (PhysiCLeAR at 240 × 320 × 3 × 25 is 2.7 GB so and
//! 11 GB as f32), with each touch's gel before contact (`background`) subtracted only as a touch
//! is read. Every reader sees f32 values either way ([`Frames::sample`]).

use std::borrow::Cow;

/// Touches back to back, each `rows` rows (its pixels or taxels, and colours) of `frames` values.
#[derive(Clone, Debug, PartialEq)]
pub enum Frames {
    F32(Vec<f32>),
    /// A camera's frames; `background`, one value a row of each touch, is subtracted as they are read.
    U8 {
        x: Vec<u8>,
        background: Option<Vec<u8>>,
    },
}

impl From<Vec<f32>> for Frames {
    fn from(x: Vec<f32>) -> Self {
        Self::F32(x)
    }
}

impl Frames {
    /// Touch `i` of `len` values, `frames` a row, as f32: borrowed where stored so, else read
    /// from the 8-bit frames minus the background.
    pub fn sample(&self, i: usize, len: usize, frames: usize) -> Cow<'_, [f32]> {
        match self {
            Self::F32(x) => Cow::Borrowed(&x[i * len..(i + 1) * len]),
            Self::U8 { x, background } => {
                let rows = len / frames;
                let values = x[i * len..(i + 1) * len].chunks(frames).enumerate().flat_map(|(r, row)| {
                    let b = background.as_ref().map_or(0.0, |b| f32::from(b[i * rows + r]));
                    row.iter().map(move |v| f32::from(*v) - b)
                });
                Cow::Owned(values.collect())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eight_bit_frames_read_as_their_values_minus_the_background_of_each_row() {
        // Two touches of two rows of three frames; a background value for each touch's rows.
        let frames = Frames::U8 { x: (0..12).map(|v| 10 * v).collect(), background: Some(vec![5, 0, 100, 255]) };
        assert_eq!(frames.sample(0, 6, 3).as_ref(), &[-5.0, 5.0, 15.0, 30.0, 40.0, 50.0]);
        assert_eq!(frames.sample(1, 6, 3).as_ref(), &[-40.0, -30.0, -20.0, -165.0, -155.0, -145.0]);
        let plain = Frames::U8 { x: vec![0, 255], background: None };
        assert_eq!(plain.sample(0, 2, 2).as_ref(), &[0.0, 255.0]);
        let floats = Frames::from(vec![0.5, -1.0, 2.0, 3.0]);
        assert!(matches!(floats.sample(1, 2, 2), Cow::Borrowed(&[2.0, 3.0])));
    }
}
