//! `pvt3 export` and `pvt3 bake`: a (pruned) checkpoint baked into smaller dense weights, and
//! written as one ONNX file.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use pvt3_trainer::checkpoint::BakedFile;
use pvt3_trainer::json;

/// Write a model as one ONNX file (opset 17): raw frames in, normalisation and kept-frame
/// selection inside, logits and probabilities out.
#[derive(clap::Args)]
pub struct ExportArgs {
    /// A run or checkpoint directory (baked on the way), or a file written by `pvt3 bake`.
    pub model: PathBuf,
    #[arg(long, short, default_value = "model.onnx")]
    pub out: PathBuf,
}

/// Bake a (pruned) checkpoint into a smaller dense model: pruned channels and frames removed.
#[derive(clap::Args)]
pub struct BakeArgs {
    /// The run (or checkpoint) directory.
    pub run: PathBuf,
    /// Output file (JSON: the baked weights, normalisation, class names, provenance).
    #[arg(long, short, default_value = "baked.json")]
    pub out: PathBuf,
}

/// Bakes (if needed) and exports `model` to `out`.
/// Exports the checkpoint or baked file `model` to `out`; what was written, in words.
pub fn export_onnx(model: &Path, out: &Path) -> Result<String> {
    let file = BakedFile::load(model)?;
    let onnx = pvt3_export::export(&file.baked, &file.normalization, &file.metadata())
        .with_context(|| format!("exporting {}", model.display()))?;
    pvt3_export::write(&onnx, out)?;
    Ok(format!("wrote {}: {}", out.display(), file.baked.size_summary()))
}

pub fn bake(a: BakeArgs) -> Result<()> {
    let file = BakedFile::from_checkpoint(&a.run)?;
    json::write_json_atomically(&a.out, &file)?;
    let baked = &file.baked;
    println!(
        "baked {}: {} → {} parameters, {} → {} multiply-adds per sample, {} of {} temporal tokens kept",
        a.out.display(),
        baked.config.parameter_count() + baked.config.time_tokens(),
        baked.parameter_count(),
        baked.config.mult_adds(),
        baked.mult_adds(),
        baked.kept_tokens.len(),
        baked.config.time_tokens()
    );
    Ok(())
}
