//! `pvt3 import`: a folder of CSV recordings ([`csv`]), or of a camera's videos or frame folders
//! ([`camera`]), → a data set (`.npz`) the trainer reads. Both find their touches alike
//! ([`folder`]) and write what every set records beside its frames alike ([`npz`]).
//!
//! The folder holds one folder per class (its name is the class's), each with one CSV file per
//! touch: a header row, then one row per frame. Or, with a file name pattern that names the
//! class (`{class}_F{force}_V{speed}_*`), the CSV files side by side in one folder. Which columns
//! are sensor channels is chosen by name or pattern, or by default every numeric column that
//! varies, time-stamp-like columns left out (and said so). Touches may differ in length; the set
//! records each touch's (`lengths`), its file (`sources`), the class names (`class_names`) and
//! the conditions the pattern reads from the names (speed, force, …), see [`crate::data::key`].

pub mod camera;
pub mod csv;
mod decode;
pub mod folder;
pub mod labels;
mod npz;
