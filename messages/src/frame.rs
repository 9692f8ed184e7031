//! A message made a frame: [`decode`] reads a message of a [`Kind`] and gives its stamp and its
//! frame, a camera's [`Picture`] (8-bit, RGB or grey) or a grid of values.

use pvt3_format::Picture;

use crate::cdr::Reader;
use crate::msg::{CompressedImage, Image, MultiArray};
use crate::{DecodeError, Kind, Result, Stamp};

/// One frame as pvt3 reads it.
#[derive(Clone, Debug, PartialEq)]
pub enum Frame {
    /// A camera's frame: RGB (the colour order converted, alpha dropped) or grey, 8-bit (16-bit
    /// samples cut to their high byte, as a 16-bit PNG frame is read), rows unpadded.
    Picture(Picture),
    /// A taxel array's values, row-major, with its layout's dimensions (`layout.dim`'s sizes; none
    /// where the message gives none).
    Values {
        /// The values.
        values: Vec<f32>,
        /// The layout's dimensions, outermost first.
        dims: Vec<usize>,
    },
}

/// A decoded message: its frame and, where the message has a header, its stamp.
#[derive(Clone, Debug, PartialEq)]
pub struct Decoded {
    /// `header.stamp`, where the type has a header.
    pub stamp: Option<Stamp>,
    /// The frame.
    pub frame: Frame,
}

/// The message of type `kind` in `cdr` (its serialised bytes, encapsulation header first) as a
/// frame, or why it is not one.
pub fn decode(kind: Kind, cdr: &[u8]) -> Result<Decoded> {
    let mut r = Reader::new(cdr)?;
    match kind {
        Kind::Image => {
            let image = Image::read(&mut r)?;
            Ok(Decoded { stamp: Some(image.stamp), frame: Frame::Picture(picture(&image)?) })
        }
        Kind::CompressedImage => {
            let image = CompressedImage::read(&mut r)?;
            Ok(Decoded { stamp: Some(image.stamp), frame: Frame::Picture(compressed(&image)?) })
        }
        Kind::MultiArray(element) => {
            let array = MultiArray::read(&mut r, element)?;
            let dims: Vec<usize> = array.dims.iter().map(|(_, size)| *size).collect();
            let held = dims.iter().try_fold(1usize, |n, d| n.checked_mul(*d));
            if !dims.is_empty() && held.is_none_or(|n| n > array.values.len()) {
                let why = format!("layout.dim {dims:?} holds more values than the message's {}", array.values.len());
                return Err(DecodeError(why));
            }
            let values = if dims.is_empty() { array.values } else { array.values[..held.unwrap_or(0)].to_vec() };
            Ok(Decoded { stamp: None, frame: Frame::Values { values, dims } })
        }
    }
}

/// The encodings of `sensor_msgs/msg/Image` pvt3 reads: (name, channels, bytes a sample, the
/// channels' order as RGB indices, or grey).
const ENCODINGS: [(&str, usize, usize, Option<[usize; 3]>); 6] = [
    ("rgb8", 3, 1, Some([0, 1, 2])),
    ("bgr8", 3, 1, Some([2, 1, 0])),
    ("rgba8", 4, 1, Some([0, 1, 2])),
    ("bgra8", 4, 1, Some([2, 1, 0])),
    ("mono8", 1, 1, None),
    ("mono16", 1, 2, None),
];

/// An image's pixels as an RGB or grey picture.
fn picture(image: &Image) -> Result<Picture> {
    let encoding = image.encoding.to_ascii_lowercase();
    let Some(&(_, channels, sample, order)) = ENCODINGS.iter().find(|e| e.0 == encoding) else {
        let known: Vec<&str> = ENCODINGS.iter().map(|e| e.0).collect();
        return Err(DecodeError(format!("encoding `{}` is not one pvt3 reads ({})", image.encoding, known.join(", "))));
    };
    let (height, width, step) = (image.height as usize, image.width as usize, image.step as usize);
    let row = width * channels * sample;
    if step < row || image.data.len() != height * step || height == 0 || width == 0 {
        return Err(DecodeError(format!(
            "a {width} × {height} {encoding} image needs rows of at least {row} bytes (step {step}) and height × step bytes, {} here",
            image.data.len()
        )));
    }
    let pixel = channels * sample;
    // The high byte of a sample: its first in big-endian order, its last in little-endian.
    let high = if sample == 2 && !image.is_bigendian { 1 } else { 0 };
    let out = if order.is_some() { 3 } else { 1 };
    let mut data = Vec::with_capacity(height * width * out);
    for r in image.data.chunks_exact(step).map(|r| &r[..row]) {
        for p in r.chunks_exact(pixel) {
            match order {
                Some(rgb) => data.extend(rgb.map(|c| p[c])),
                None => data.push(p[high]),
            }
        }
    }
    Ok(Picture { height, width, channels: out, data })
}

/// A compressed image's picture: PNG or JPEG, by its format or, where the format names neither,
/// by its first bytes.
fn compressed(image: &CompressedImage) -> Result<Picture> {
    let format = image.format.to_ascii_lowercase();
    let png = image.data.starts_with(b"\x89PNG");
    let decoded = if format.contains("png") || (png && !format.contains("jpeg")) {
        crate::png(image.data)
    } else if format.contains("jpeg") || format.contains("jpg") || image.data.starts_with(&[0xff, 0xd8]) {
        crate::jpeg(image.data)
    } else {
        Err(format!("format `{}` is neither png nor jpeg", image.format))
    };
    decoded.map_err(DecodeError)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::msg::Element;

    /// Pads a CDR message to 4-byte alignment (from the end of its header).
    fn align4(m: &mut Vec<u8>) {
        while !(m.len() - 4).is_multiple_of(4) {
            m.push(0);
        }
    }

    /// The CDR of an Image: a header stamped 3 s 4 ns, then `fields`.
    fn image(height: u32, width: u32, encoding: &str, bigendian: bool, step: u32, data: &[u8]) -> Vec<u8> {
        let mut m = vec![0, 1, 0, 0];
        let string = |m: &mut Vec<u8>, s: &str| {
            align4(m);
            m.extend_from_slice(&(s.len() as u32 + 1).to_le_bytes());
            m.extend_from_slice(s.as_bytes());
            m.push(0);
        };
        let u32 = |m: &mut Vec<u8>, v: u32| {
            align4(m);
            m.extend_from_slice(&v.to_le_bytes());
        };
        u32(&mut m, 3);
        u32(&mut m, 4);
        string(&mut m, "cam");
        u32(&mut m, height);
        u32(&mut m, width);
        string(&mut m, encoding);
        m.push(u8::from(bigendian));
        u32(&mut m, step);
        u32(&mut m, data.len() as u32);
        m.extend_from_slice(data);
        m
    }

    fn picture_of(cdr: &[u8]) -> Result<Picture> {
        let decoded = decode(Kind::Image, cdr)?;
        assert_eq!(decoded.stamp, Some(Stamp { sec: 3, nanosec: 4 }));
        match decoded.frame {
            Frame::Picture(p) => Ok(p),
            Frame::Values { .. } => unreachable!(),
        }
    }

    #[test]
    fn every_encoding_becomes_rgb_or_grey_without_padding() {
        // One row of two pixels, padded by two bytes.
        let bgr = picture_of(&image(1, 2, "bgr8", false, 8, &[1, 2, 3, 4, 5, 6, 99, 99])).unwrap();
        assert_eq!((bgr.shape(), bgr.data), ([1, 2, 3], vec![3, 2, 1, 6, 5, 4]));
        let bgra = picture_of(&image(1, 2, "bgra8", false, 8, &[1, 2, 3, 0, 4, 5, 6, 0])).unwrap();
        assert_eq!(bgra.data, [3, 2, 1, 6, 5, 4]);
        let mono16 = picture_of(&image(1, 2, "mono16", false, 4, &[0x34, 0x12, 0x78, 0x56])).unwrap();
        assert_eq!((mono16.shape(), mono16.data), ([1, 2, 1], vec![0x12, 0x56]), "the high byte, little-endian");
        let big = picture_of(&image(1, 2, "mono16", true, 4, &[0x12, 0x34, 0x56, 0x78])).unwrap();
        assert_eq!(big.data, [0x12, 0x56], "the high byte, big-endian");
    }

    #[test]
    fn images_that_disagree_with_their_sizes_are_refused() {
        let refused = [
            (
                image(2, 2, "rgb8", false, 6, &[0; 11]),
                "a 2 × 2 rgb8 image needs rows of at least 6 bytes (step 6) and height × step bytes, 11 here",
            ),
            (image(1, 2, "rgb8", false, 5, &[0; 5]), "rows of at least 6 bytes (step 5)"),
            (image(0, 2, "rgb8", false, 6, &[]), "a 2 × 0 rgb8 image"),
            (image(1, 1, "yuv422", false, 2, &[0; 2]), "encoding `yuv422` is not one pvt3 reads (rgb8, bgr8"),
        ];
        for (cdr, why) in refused {
            let err = picture_of(&cdr).unwrap_err().0;
            assert!(err.contains(why), "{err}");
        }
        let whole = image(1, 2, "rgb8", false, 6, &[0; 6]);
        let err = decode(Kind::Image, &whole[..whole.len() - 1]).unwrap_err().0;
        assert!(err.starts_with("truncated: data at byte"), "{err}");
        let err = decode(Kind::CompressedImage, &whole).unwrap_err().0;
        assert!(err.contains("neither png nor jpeg") || err.contains("truncated"), "an Image read as CompressedImage: {err}");
    }

    #[test]
    fn a_multi_array_gives_its_values_from_its_offset_with_its_grid() {
        // layout.dim: [("rows", 2, 6), ("cols", 3, 3)], data_offset 1, data: int16 × 7.
        let mut m = vec![0, 1, 0, 0, 2, 0, 0, 0];
        for (label, size, stride) in [("rows", 2u32, 6u32), ("cols", 3, 3)] {
            m.extend_from_slice(&(label.len() as u32 + 1).to_le_bytes());
            m.extend_from_slice(label.as_bytes());
            m.push(0);
            align4(&mut m);
            m.extend_from_slice(&size.to_le_bytes());
            m.extend_from_slice(&stride.to_le_bytes());
        }
        m.extend_from_slice(&1u32.to_le_bytes());
        m.extend_from_slice(&7u32.to_le_bytes());
        for v in [-9i16, 1, 2, 3, 4, 5, 6] {
            m.extend_from_slice(&v.to_le_bytes());
        }
        let decoded = decode(Kind::MultiArray(Element::I16), &m).unwrap();
        assert_eq!(decoded.frame, Frame::Values { values: vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0], dims: vec![2, 3] });
        assert_eq!(decoded.stamp, None);
        m.truncate(m.len() - 2);
        let err = decode(Kind::MultiArray(Element::I16), &m).unwrap_err().0;
        assert!(err.contains("truncated: data"), "{err}");
    }
}
