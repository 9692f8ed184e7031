//! PVT³, the pruned video-vision transformer for tactile texture classification, in candle.
//!
//! A tactile recording `[batch, height, width, (channels,) frames]` is cut into spatial patches per
//! frame (or per tubelet of frames), encoded by a spatial transformer per frame and a temporal
//! transformer across frames (the ViViT factorised encoder), and classified from the temporal CLS
//! token. Trainable *channel-selection* masks (attention q/k/v channels, feed-forward units) and a
//! *frame-selection* mask let training find what can be pruned. The paper's baselines, ViT and
//! RAEC, live beside it so that one trainer fits all three ([`Model`]).
//!
//! What the model is without a tensor library (configuration, cost model, pruning, baking, the
//! f64 reference) lives in `pvt3-spec`; this crate is its candle form for training.

pub mod attention;
pub mod dense;
pub mod dropout;
pub mod error;
pub mod feed_forward;
pub mod fused_block;
pub mod fused_embed;
#[cfg(test)]
mod gradcheck;
pub mod head;
pub mod init;
pub mod layer_norm;
pub mod lstm;
pub mod model;
pub mod pvt3;
pub mod raec;
pub mod spectrum;
pub mod transformer;
pub mod vit;
pub mod weights;

pub use model::Model;
pub use error::{Error, Result};
pub use pvt3::Pvt3;
pub use pvt3_spec::{Architecture, Config, Network, Pvt3Config, RaecConfig, Rng, VitConfig};
