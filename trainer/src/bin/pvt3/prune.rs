//! `pvt3 prune`: prune a trained run by its mask scores (or at random), then fine-tune it.

use std::path::PathBuf;

use anyhow::{Context, Result};
use pvt3_trainer::checkpoint;
use pvt3_trainer::prune::prune_and_fine_tune;

use crate::progress;
use crate::prune_args::{report_pruned, PruneArgs};

/// Prune a trained run by its mask scores, then fine-tune it with the pruned entries held at zero.
#[derive(clap::Args)]
pub struct PruneCommand {
    /// The trained run (or checkpoint) directory.
    pub run: PathBuf,
    /// Data set (default: the one the run was trained on).
    #[arg(long)]
    pub data: Option<PathBuf>,
    /// The pruned run's directory (checkpoint in OUT/model, resume state in OUT/last).
    #[arg(long, short, default_value = "runs/pruned")]
    pub out: PathBuf,
    /// Continue the interrupted fine-tuning in OUT.
    #[arg(long)]
    pub resume: bool,
    #[command(flatten)]
    pub prune: PruneArgs,
}

pub fn run(a: PruneCommand) -> Result<()> {
    let stage = a.prune.stage().context("give --prune-channels, --prune-frames and/or --prune-weights")?;
    let (_, meta) = checkpoint::load_meta(&a.run)?;
    let data_path = a.data.clone().unwrap_or_else(|| PathBuf::from(&meta.provenance.data));
    if let Some(note) = meta.provenance.split_note() {
        eprintln!("{note}");
    }
    let dataset = meta.provenance.dataset(a.data.as_deref()).with_context(|| format!("loading {}", data_path.display()))?;
    let bar = progress::bar("fine-tune");
    if let Some(p) = prune_and_fine_tune(&a.run, &dataset, &stage, &a.out, a.resume, &bar)? {
        bar.finish();
        println!("{}", report_pruned(&p, &a.out)?);
    }
    Ok(())
}
