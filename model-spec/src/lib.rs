//! PVT³ as plain data, without candle: what the model is ([`Config`] and its presets, the cost
//! model), what it becomes once pruned ([`prune`] plans, [`bake`] into [`baked::BakedPvt3`]) and
//! what it computes ([`reference`], the f64 forward every other form of the model is held to).
//!
//! The trainer's candle modules (`pvt3-models`) build on it; the exporter needs nothing else, so
//! writing an `.onnx` builds no tensor library.

pub mod bake;
pub mod baked;
pub mod config;
pub mod error;
pub mod names;
pub mod normalization;
pub mod prune;
pub mod reference;
pub mod rng;
pub mod sensor;
pub mod spectrum;
pub mod weights;

pub use config::{Architecture, Config, Network, Pvt3Config, RaecConfig, VitConfig};
pub use error::{Error, Result};
pub use rng::Rng;
pub use sensor::Sensor;
