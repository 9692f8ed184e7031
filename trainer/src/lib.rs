//! The pvt3 trainer: data sets, normalisation, training, cross-validation, checkpoints and
//! evaluation for PVT³. The `pvt3` binary is a thin command line over this library.

pub mod anytime;
pub mod atomic;
pub mod average;
pub mod bench;
pub mod checkpoint;
pub mod configure;
pub mod crash;
pub mod cv;
pub mod data;
pub mod distill;
pub mod error;
pub mod evaluate;
pub mod final_model;
pub mod info;
pub mod joint;
pub mod json;
pub mod metrics;
pub mod optim;
pub mod options;
pub mod plot;
pub mod provenance;
pub mod prune;
pub mod run_dir;
pub mod schedule;
pub mod spectrum_fit;
pub mod stopping;
pub mod stress;
pub mod train;

pub use error::{Error, Result};
