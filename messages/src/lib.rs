//! The ROS 2 messages a tactile sensor's driver publishes, read as pvt3's frames. A camera
//! (DIGIT, GelSight Mini) publishes `sensor_msgs/msg/Image` or `CompressedImage`; a taxel skin or
//! pressure array publishes a `std_msgs/msg/*MultiArray`. Each is read from its CDR bytes (the
//! serialisation ROS 2 uses on the wire and in bags, [`cdr`]) by its definition ([`msg`]), then
//! made a frame ([`Frame`]): a [`Picture`] in RGB or grey, 8-bit, whatever the encoding, colour
//! order, row padding or depth; or a grid of values.
//!
//! `pvt3 import` reads bags with this code and a node on the robot reads its topic with it, so
//! that the robot's frames are the training's by construction, not by two hand-written decoders
//! that agree.

#![warn(missing_docs)]

pub mod cdr;
mod compressed;
mod frame;
pub mod msg;

pub use compressed::{jpeg, png};
pub use frame::{decode, Decoded, Frame};
pub use msg::{Kind, Stamp};
pub use pvt3_format::Picture;

/// Why a message is not a frame: its bytes end early or hold what its type cannot, or its
/// encoding is not one pvt3 reads. The text names the field and the byte at fault.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct DecodeError(pub String);

/// The results of decoding.
pub type Result<T> = std::result::Result<T, DecodeError>;
