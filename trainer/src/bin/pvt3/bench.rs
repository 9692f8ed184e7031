//! `pvt3 bench`: training throughput in candle, and the runtime's numerical stress.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Subcommand;
use pvt3_models::Config;
use pvt3_trainer::bench::train_speed;
use pvt3_trainer::checkpoint::BakedFile;
use pvt3_trainer::options::TrainOptions;

#[derive(Subcommand)]
pub enum Bench {
    /// Training throughput of a preset in candle on random inputs, as one JSON line.
    Train {
        #[arg(long, default_value = "icub20")]
        preset: String,
        /// Timed optimiser steps (after two untimed warm-up steps).
        #[arg(long, default_value_t = 20)]
        steps: usize,
        /// Run the model composed of candle ops instead of its fused ops (each transformer block,
        /// the embedding), to measure what the fusion gains (the same function).
        #[arg(long)]
        composed: bool,
        /// Dropout (default: the preset's, 0.1).
        #[arg(long)]
        dropout: Option<f64>,
        #[command(flatten)]
        options: Box<TrainOptions>,
    },
    /// Numerical stress of the robot runtime: the exported model's f32 logits against the baked
    /// f64 reference on extreme inputs and folded weights; prints a markdown table (docs/benchmarks.md).
    Stress {
        /// A run or checkpoint directory, or a file from `pvt3 bake`.
        model: PathBuf,
        /// Random windows per case.
        #[arg(long, default_value_t = 8)]
        windows: usize,
    },
}

pub fn run(b: Bench) -> Result<()> {
    match b {
        Bench::Train { preset, steps, composed, dropout, options } => {
            pvt3_models::transformer::use_composed_ops(composed);
            let cfg = Config::preset(&preset)?;
            let cfg = Config { dropout: dropout.unwrap_or(cfg.dropout), ..cfg };
            let mut speed = train_speed(&cfg, &options, 2, steps)?;
            if composed {
                speed.framework = "candle, composed ops";
            }
            println!("{}", serde_json::to_string(&speed)?);
        }
        Bench::Stress { model, windows } => {
            let file = BakedFile::load(&model).with_context(|| format!("loading {}", model.display()))?;
            let scratch = std::env::temp_dir().join(format!("pvt3-stress-{}", std::process::id()));
            std::fs::create_dir_all(&scratch)?;
            let rows = pvt3_trainer::stress::stress(&file, windows, false, &scratch);
            std::fs::remove_dir_all(&scratch)?;
            print!("{}", pvt3_trainer::stress::table(&rows?));
        }
    }
    Ok(())
}
