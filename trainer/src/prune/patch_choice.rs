//! Choosing the patches to prune by the validation fold. A patch mask trained like the frame
//! mask stays close to one (docs/camera.md, "Patch selection"), so its magnitudes say little about
//! which patches a class needs; the validation fold says it directly. One patch at a time, the patch
//! without which the validation loss is lowest goes (greedy backward elimination): a patch count
//! times the removed count evaluations of the validation fold, and no test touch read. A head over
//! the image's space reads a removed patch's pixels as 0 with its map as fitted (the fine-tuning
//! fits it again), so the loss weighs what the head loses with the patch too.

use std::path::Path;

use candle_core::{Device, Tensor};
use candle_nn::VarMap;
use indicatif::ProgressBar;
use pvt3_models::Model;
use pvt3_spec::names;
use pvt3_spec::prune::{PatchChoice, Plan};

use super::PruneStage;
use crate::checkpoint::Meta;
use crate::data::windows::Samples;
use crate::data::Dataset;
use crate::evaluate::evaluate;
use crate::{Error, Result};

/// The patches `stage` keeps where not by magnitude (`None`): those it names (a final model's), or
/// those the validation fold of `parent`, loaded, chooses ([`by_validation`]), as many removed as
/// `plan` removes.
pub fn kept(
    stage: &PruneStage,
    parent: &Path,
    (meta, model, varmap): (&Meta, &Model, &VarMap),
    data: &Dataset,
    plan: &Plan,
    bar: &ProgressBar,
) -> Result<Option<Vec<bool>>> {
    if let Some(kept) = &stage.kept_patches {
        return Ok(Some(kept.clone()));
    }
    if stage.spec.patches == 0.0 || stage.spec.patch_choice != PatchChoice::Validation {
        return Ok(None);
    }
    let validation = data.split_for(meta.provenance.val_fold)?.val;
    if validation.is_empty() {
        let why = format!("{} has no validation fold to choose patches by; prune it with --patch-choice magnitude", parent.display());
        return Err(Error::Usage(why));
    }
    let removed = plan[names::PATCH_MASK].iter().filter(|k| !**k).count();
    let samples = Samples::new(data, &validation, &meta.normalization);
    by_validation(model, varmap, &samples, removed, bar).map(Some)
}

/// Which patches to keep so that `remove` are gone, patches already zero among them: the
/// model's patch mask (in `varmap`) set to zero patch by patch, scored on `validation`, and
/// restored after.
pub fn by_validation(model: &Model, varmap: &VarMap, validation: &Samples, remove: usize, bar: &ProgressBar) -> Result<Vec<bool>> {
    let var = varmap.data().lock().expect("varmap lock poisoned").get(names::PATCH_MASK).cloned();
    let var = var.ok_or_else(|| Error::Usage("choosing patches by validation needs a model with a patch mask".into()))?;
    let trained = var.as_tensor().to_vec1::<f32>()?;
    let mut keep: Vec<bool> = trained.iter().map(|v| *v != 0.0).collect();
    let loss_without = |keep: &[bool], patch: usize| -> Result<f64> {
        let values: Vec<f32> = trained.iter().enumerate().map(|(p, v)| if keep[p] && p != patch { *v } else { 0.0 }).collect();
        var.set(&Tensor::from_vec(values, trained.len(), &Device::Cpu)?)?;
        Ok(evaluate(model, validation)?.loss)
    };
    while keep.iter().filter(|k| !**k).count() < remove.min(keep.len()) {
        let mut best: Option<(f64, usize)> = None;
        for patch in (0..keep.len()).filter(|&p| keep[p]) {
            let loss = loss_without(&keep, patch)?;
            bar.set_message(format!("choosing patches by validation: {} of {remove} removed", keep.iter().filter(|k| !**k).count()));
            if best.is_none_or(|(l, _)| loss < l) {
                best = Some((loss, patch));
            }
        }
        keep[best.expect("a kept patch is left while fewer than all are removed").1] = false;
    }
    var.set(&Tensor::from_vec(trained.clone(), trained.len(), &Device::Cpu)?)?;
    Ok(keep)
}
