//! `pvt3 import`: a folder of CSV recordings ([`csv`]), or of a camera's videos, frame folders,
//! still images or ROS 2 bags ([`camera`], `bag`), → a data set (`.npz`) the trainer reads. Both find their touches
//! alike ([`folder`]: one folder per class, side by side with a `--name` pattern that names the
//! class, or as a labels file lists them, [`labels`]) and write what every set records beside its
//! frames alike ([`npz`]: each touch's file and conditions, the class names; [`crate::data::key`]).

#[cfg(feature = "bags")]
pub mod bag;
pub mod camera;
pub mod csv;
mod decode;
pub mod folder;
pub mod labels;
mod npz;
pub mod timing;
