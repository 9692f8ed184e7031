//! The paper's schedule after training: prune a run by its selection-mask scores, then fine-tune
//! with the pruned entries held at zero. The fine-tuned run is an ordinary run directory whose
//! provenance records the pruning.

use std::path::Path;

use indicatif::ProgressBar;
use pvt3_models::weights::varmap_tensors;
use pvt3_spec::names;
use pvt3_spec::prune::{self, PruneSpec};

use crate::checkpoint;
use crate::data::Dataset;
use crate::options::{HeldZeros, Optimization, TrainOptions};
use crate::train::{train, RunResult, RunSpec};
use crate::Result;

/// What to prune and how long to fine-tune.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PruneStage {
    pub spec: PruneSpec,
    pub epochs: usize,
    pub lr: f64,
    /// The patches to keep, where decided before (a final model's: those its cross-validation's
    /// pruned runs kept most often, [`crate::final_model`]); `None`: chosen as `spec` says.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kept_patches: Option<Vec<bool>>,
}

/// Mixed into the run's seed to draw the weights that random pruning zeroes.
const RANDOM_WEIGHTS_SEED: u64 = 0x007a_110f_5eed;

/// Prunes the checkpoint of `parent` and fine-tunes it into `out` on the parent's split of `data`.
pub fn prune_and_fine_tune(
    parent: &Path,
    data: &Dataset,
    stage: &PruneStage,
    out: &Path,
    resume: bool,
    bar: &ProgressBar,
) -> Result<Option<RunResult>> {
    let (meta, model, varmap) = checkpoint::load(parent)?;
    if let Some(recorded) = &meta.provenance.trained_on {
        data.check_split(recorded, &format!("the pruned run {}", parent.display()))?;
    }
    let mut tensors = varmap_tensors(&varmap)?;
    let mut plan = prune::plan(&meta.config, &tensors, &stage.spec)?;
    if let Some(kept) = patch_choice::kept(stage, parent, (&meta, &model, &varmap), data, &plan, bar)? {
        plan.insert(names::PATCH_MASK.into(), kept);
    }
    prune::apply(&plan, &mut tensors);
    let parent_options = meta.provenance.options;
    if stage.spec.weights > 0.0 {
        prune::random_weights(&mut tensors, stage.spec.weights, parent_options.seed ^ RANDOM_WEIGHTS_SEED)?;
    }
    let optimization = Optimization {
        epochs: stage.epochs,
        lr: stage.lr,
        warmup_epochs: parent_options.optimization.warmup_epochs.min(1),
        ..parent_options.optimization
    };
    let options = TrainOptions {
        optimization,
        held: HeldZeros { pruned: true, zero_weights: stage.spec.weights > 0.0 },
        // A model of a joint run is pruned and fine-tuned alone.
        joint: None,
        ..parent_options
    };
    let spec = RunSpec {
        data,
        config: meta.config,
        val_fold: meta.provenance.val_fold,
        options,
        classes: meta.classes,
        pause_after: None,
        start: Some(tensors),
        pruning: Some(stage.spec.clone()),
        partner: None,
    };
    train(&spec, out, resume, bar)
}

mod patch_choice;

#[cfg(test)]
mod tests;
