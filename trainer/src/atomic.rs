//! Files and directories replaced whole: written under a temporary name beside the target, then
//! renamed over it, so that a reader never sees half of one and a crash leaves the previous
//! version. Below everything a run stores: checkpoints, JSON records, pictures.
//! - [`file`]: a file, in one rename; a killed writer's temporaries are removed on reopening.
//! - [`dir`]: a directory, in two renames, with the `.old` copy a crash between them leaves.

pub mod dir;
pub mod file;
