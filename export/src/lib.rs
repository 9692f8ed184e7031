//! Export a baked PVT³ to ONNX (opset 17): one file that takes raw sensor frames in the data
//! set's own layout (batch dimension symbolic), normalises them and gathers the kept frames
//! inside the graph, and outputs logits and class probabilities. Metadata properties name the
//! classes, the input layout, the kept frames, the configuration and where the model came from,
//! and a digest covers all of it (names, keys and digest live in `pvt3-format`, the contract the
//! runtime reads too).
//!
//! Depends on the baked form only: pruned channels and frames are already gone, so the graph
//! computes the spatial transformer for the kept frames alone. Named seams between the spatial
//! and the temporal stage let the runtime stream a touch frame by frame from the same file.

mod attention;
mod embedding;
mod error;
mod graph;
mod layers;
mod model;
mod spectrum;

pub use error::{Error, Result};
pub use model::{export, write, Metadata};
