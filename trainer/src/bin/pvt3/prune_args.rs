//! The pruning options of `train`, `cv` and `prune`, and what a pruned run reports.

use std::path::Path;

use anyhow::Result;
use pvt3_spec::prune::{PatchChoice, PruneSpec, Scope};
use pvt3_trainer::checkpoint::BakedFile;
use pvt3_trainer::prune::PruneStage;
use pvt3_trainer::run_dir::Run;
use pvt3_trainer::train::RunResult;

/// Pruning after training (the paper's schedule: train, prune, fine-tune).
#[derive(clap::Args)]
pub struct PruneArgs {
    /// Prune this percentage of channels (attention q/k/v channels and FFN units) by mask score.
    #[arg(long)]
    prune_channels: Option<f64>,
    /// Prune this percentage of frames (temporal tokens) by mask score.
    #[arg(long)]
    prune_frames: Option<f64>,
    /// Prune this percentage of the patch grid, chosen as --patch-choice says: a pruned patch's pixels are never
    /// embedded, and the exported model never normalises or embeds them. Needs a model with a
    /// patch mask (`--set patch_selection=true`).
    #[arg(long)]
    prune_patches: Option<f64>,
    /// How --prune-patches chooses the patches: `validation` removes, one at a time, the patch
    /// without which the run's validation fold has the lowest loss; `magnitude` the smallest
    /// patch-mask values.
    #[arg(long, value_enum, default_value_t = PatchChoice::Validation)]
    patch_choice: PatchChoice,
    /// Persistent random pruning (the PVT³ report's "random pruning"): this percentage of every
    /// weight matrix's entries set to zero at random after training, then fine-tuned with them
    /// held at zero. A regulariser: the matrices stay dense, the model no smaller.
    #[arg(long)]
    prune_weights: Option<f64>,
    /// How --prune-channels shares the pruning among the masks.
    #[arg(long, value_enum, default_value_t = Scope::Local)]
    prune_scope: Scope,
    /// Epochs of fine-tuning after pruning, pruned entries held at zero.
    #[arg(long, default_value_t = 30)]
    fine_tune_epochs: usize,
    /// Peak learning rate of the fine-tuning.
    #[arg(long, default_value_t = 5e-4)]
    fine_tune_lr: f64,
}

impl PruneArgs {
    pub fn stage(&self) -> Option<PruneStage> {
        if [self.prune_channels, self.prune_frames, self.prune_patches, self.prune_weights].iter().all(Option::is_none) {
            return None;
        }
        Some(PruneStage {
            spec: PruneSpec {
                channels: self.prune_channels.unwrap_or(0.0),
                frames: self.prune_frames.unwrap_or(0.0),
                patches: self.prune_patches.unwrap_or(0.0),
                scope: self.prune_scope,
                weights: self.prune_weights.unwrap_or(0.0),
                patch_choice: self.patch_choice,
            },
            epochs: self.fine_tune_epochs,
            lr: self.fine_tune_lr,
            kept_patches: None,
        })
    }
}

pub fn report_pruned(r: &RunResult, out: &Path) -> Result<String> {
    let baked = BakedFile::from_checkpoint(out)?.baked;
    Ok(format!(
        "pruned and fine-tuned: best epoch {} of {}, validation {:.4}, test {:.4}; baked: {}; checkpoint {}",
        r.best_epoch,
        r.epochs,
        r.val_accuracy,
        r.test_accuracy,
        baked.size_summary(),
        Run(out).model().display()
    ))
}
