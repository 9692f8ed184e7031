//! `pvt3 info`: parameters, multiply-adds and shapes of a preset, a configuration or a checkpoint
//! (and a PVT³ checkpoint's size after baking).

use std::path::Path;

use anyhow::Result;
use pvt3_models::Architecture;
use pvt3_trainer::checkpoint::BakedFile;
use pvt3_trainer::info::report;

use pvt3_trainer::configure::resolve_config;

/// Parameters, multiply-adds and tensor shapes of a preset, a JSON config or a checkpoint.
#[derive(clap::Args)]
pub struct InfoArgs {
    /// A preset name, a config .json, or a checkpoint directory.
    #[arg(default_value = "icub20")]
    pub model: String,
    /// Print the configuration as JSON instead.
    #[arg(long)]
    pub json: bool,
}

pub fn run(a: InfoArgs) -> Result<()> {
    // A PVT³ checkpoint is read once: its configuration, and its size after baking.
    let cfg = resolve_config(&a.model)?;
    let baked = match Path::new(&a.model).is_dir() && cfg.architecture() == Architecture::Pvt3 {
        true => Some(BakedFile::from_checkpoint(Path::new(&a.model))?.baked),
        false => None,
    };
    if a.json {
        println!("{}", serde_json::to_string_pretty(&cfg)?);
    } else {
        print!("{}", report(&cfg)?);
        if let Some(b) = baked {
            println!("\nafter baking  {}", b.size_summary());
        }
    }
    Ok(())
}
