//! The message types pvt3 reads, by their ROS 2 definitions, field by field as CDR lays them
//! out: `std_msgs/msg/Header` first where a message has one.

use crate::cdr::Reader;
use crate::Result;

/// A message type pvt3 reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// `sensor_msgs/msg/Image`: raw pixels in an encoding.
    Image,
    /// `sensor_msgs/msg/CompressedImage`: a PNG or JPEG.
    CompressedImage,
    /// A `std_msgs/msg/*MultiArray`: a taxel array's values, of this element type.
    MultiArray(Element),
}

/// The element type of a multi-array.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Element {
    /// `float32`.
    F32,
    /// `float64`.
    F64,
    /// `int16`.
    I16,
    /// `int32`.
    I32,
    /// `uint16`.
    U16,
    /// `uint8`.
    U8,
}

impl Kind {
    /// Every type pvt3 reads, by its ROS 2 name, with its kind.
    pub const ALL: [(&'static str, Kind); 8] = [
        ("sensor_msgs/msg/Image", Kind::Image),
        ("sensor_msgs/msg/CompressedImage", Kind::CompressedImage),
        ("std_msgs/msg/Float32MultiArray", Kind::MultiArray(Element::F32)),
        ("std_msgs/msg/Float64MultiArray", Kind::MultiArray(Element::F64)),
        ("std_msgs/msg/Int16MultiArray", Kind::MultiArray(Element::I16)),
        ("std_msgs/msg/Int32MultiArray", Kind::MultiArray(Element::I32)),
        ("std_msgs/msg/UInt16MultiArray", Kind::MultiArray(Element::U16)),
        ("std_msgs/msg/UInt8MultiArray", Kind::MultiArray(Element::U8)),
    ];

    /// The kind of the type named `name` (`sensor_msgs/msg/Image`; ROS 1's and DDS's spellings,
    /// `sensor_msgs/Image` and `sensor_msgs::msg::dds_::Image_`, too), if pvt3 reads it.
    pub fn of(name: &str) -> Option<Kind> {
        let plain = name.replace("::", "/").replace("/dds_/", "/").trim_end_matches('_').to_string();
        Self::ALL.iter().find(|(n, _)| *n == plain || n.replacen("/msg/", "/", 1) == plain).map(|(_, k)| *k)
    }

    /// Its ROS 2 name.
    pub fn name(self) -> &'static str {
        Self::ALL.iter().find(|(_, k)| *k == self).map(|(n, _)| *n).expect("every kind is listed")
    }

    /// Whether its frames are a camera's pictures (rather than a grid of values).
    pub fn is_camera(self) -> bool {
        !matches!(self, Kind::MultiArray(_))
    }
}

/// `builtin_interfaces/msg/Time`: when a frame was taken (`header.stamp`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
pub struct Stamp {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds within the second.
    pub nanosec: u32,
}

impl Stamp {
    /// Nanoseconds since the epoch.
    pub fn nanos(self) -> i64 {
        i64::from(self.sec) * 1_000_000_000 + i64::from(self.nanosec)
    }
}

/// `std_msgs/msg/Header`: its stamp (the frame id is read and dropped).
pub fn header(r: &mut Reader) -> Result<Stamp> {
    let stamp = Stamp { sec: r.read("header.stamp.sec")?, nanosec: r.read("header.stamp.nanosec")? };
    r.string("header.frame_id")?;
    Ok(stamp)
}

/// `sensor_msgs/msg/Image`.
pub struct Image<'a> {
    /// When it was taken.
    pub stamp: Stamp,
    /// Rows.
    pub height: u32,
    /// Columns.
    pub width: u32,
    /// How a pixel is stored (`rgb8`, `bgr8`, `mono16`, …).
    pub encoding: String,
    /// Whether multi-byte samples are big-endian.
    pub is_bigendian: bool,
    /// Bytes a row, padding included.
    pub step: u32,
    /// `height × step` bytes.
    pub data: &'a [u8],
}

impl<'a> Image<'a> {
    /// The message read from `r`.
    pub fn read(r: &mut Reader<'a>) -> Result<Self> {
        Ok(Self {
            stamp: header(r)?,
            height: r.read("height")?,
            width: r.read("width")?,
            encoding: r.string("encoding")?,
            is_bigendian: r.read::<u8>("is_bigendian")? != 0,
            step: r.read("step")?,
            data: r.bytes("data")?,
        })
    }
}

/// `sensor_msgs/msg/CompressedImage`.
pub struct CompressedImage<'a> {
    /// When it was taken.
    pub stamp: Stamp,
    /// `png`, `jpeg`, or as image_transport writes it (`rgb8; jpeg compressed bgr8`).
    pub format: String,
    /// The compressed image.
    pub data: &'a [u8],
}

impl<'a> CompressedImage<'a> {
    /// The message read from `r`.
    pub fn read(r: &mut Reader<'a>) -> Result<Self> {
        Ok(Self { stamp: header(r)?, format: r.string("format")?, data: r.bytes("data")? })
    }
}

/// A `std_msgs/msg/*MultiArray`: its layout's dimensions and its values from `data_offset` on.
pub struct MultiArray {
    /// `layout.dim`: each dimension's label and size.
    pub dims: Vec<(String, usize)>,
    /// The values, as f32.
    pub values: Vec<f32>,
}

impl MultiArray {
    /// The message read from `r`, its elements of type `element`.
    pub fn read(r: &mut Reader, element: Element) -> Result<Self> {
        let n = r.length("layout.dim")?;
        // Each dimension takes at least 12 bytes: a length of one beyond what the message holds
        // fails on its first missing field, before the vector grows past the message.
        let mut dims = Vec::new();
        for _ in 0..n {
            let label = r.string("layout.dim.label")?;
            let size = r.read::<u32>("layout.dim.size")? as usize;
            r.read::<u32>("layout.dim.stride")?;
            dims.push((label, size));
        }
        let offset = r.read::<u32>("layout.data_offset")? as usize;
        let values = match element {
            Element::F32 => r.values::<f32>("data", |v| v)?,
            Element::F64 => r.values::<f64>("data", |v| v as f32)?,
            Element::I16 => r.values::<i16>("data", f32::from)?,
            Element::I32 => r.values::<i32>("data", |v| v as f32)?,
            Element::U16 => r.values::<u16>("data", f32::from)?,
            Element::U8 => r.values::<u8>("data", f32::from)?,
        };
        if offset > values.len() {
            return Err(crate::DecodeError(format!("layout.data_offset {offset} is past the {} values", values.len())));
        }
        Ok(Self { dims, values: values[offset..].to_vec() })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn types_are_named_as_ros_2_ros_1_and_dds_name_them() {
        assert_eq!(Kind::of("sensor_msgs/msg/Image"), Some(Kind::Image));
        assert_eq!(Kind::of("sensor_msgs/Image"), Some(Kind::Image));
        assert_eq!(Kind::of("sensor_msgs::msg::dds_::CompressedImage_"), Some(Kind::CompressedImage));
        assert_eq!(Kind::of("std_msgs/msg/UInt8MultiArray"), Some(Kind::MultiArray(Element::U8)));
        assert_eq!(Kind::of("std_msgs/msg/String"), None);
        for (name, kind) in Kind::ALL {
            assert_eq!(kind.name(), name);
        }
    }
}
