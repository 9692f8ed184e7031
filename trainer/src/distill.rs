//! Distillation (`--distill CV_DIR`, Hinton et al. 2015): the runs of an earlier
//! cross-validation that were trained on this run's split teach it. Each training batch's loss
//! adds `--distill-weight` × the cross-entropy between the teachers' class probabilities for the
//! whole window, averaged over the teachers, and the run's answer: to the whole window, or with
//! `--prefix-training` to its first tokens, which so learn what the whole touch will say. Several
//! runs' average errs less than one run (their errors differ); what ships is still one model.

use std::path::Path;

use candle_core::{Tensor, D};
use pvt3_models::Model;

use crate::data::normalization::Normalization;
use crate::data::TrainedOn;
use crate::run_dir::{CrossValidation, Run};
use crate::{Error, Result};

/// The teaching runs, loaded.
pub struct Teachers {
    models: Vec<Model>,
}

impl Teachers {
    /// Every trained run `cv_dir/seed*/fold{val_fold}/model`, each checked to have trained on
    /// this run's `split` (so that no teacher has learnt this run's test touches) and to read the
    /// windows this run reads (its normalisation, fitted on its training split, equal to
    /// `normalization`), to answer with the same `classes`, finished, and not the run in `out`
    /// itself (or the run it was pruned from).
    pub fn load(
        cv_dir: &Path,
        (val_fold, split): (Option<usize>, &TrainedOn),
        normalization: &Normalization,
        classes: &[String],
        out: &Path,
    ) -> Result<Self> {
        let refuse = |what: String| Error::Usage(format!("--distill {}: {what}", cv_dir.display()));
        // A final model's normalisation is fitted on every touch, a teacher's on its own split.
        let Some(val_fold) = val_fold else {
            return Err(refuse("a final model (every touch trains it) has no split a teacher could share".into()));
        };
        let absolute = |p: &Path| std::path::absolute(p).map_err(Error::io(p));
        let out = absolute(out)?;
        let mut models = Vec::new();
        for (_, _, run) in CrossValidation(cv_dir).runs()?.into_iter().filter(|(_, fold, _)| *fold == val_fold) {
            if out.starts_with(absolute(&run)?) {
                return Err(refuse(format!("{} is this run, or the run it was pruned from: a run cannot teach itself", run.display())));
            }
            if !Run(&run).result().exists() {
                return Err(refuse(format!("{} is still training (no result.json): let it finish first", run.display())));
            }
            let checkpoint = Run(&run).model();
            let (meta, model, _) = crate::checkpoint::load(&checkpoint)?;
            if let Some(why) = meta.provenance.trained_on.as_ref().and_then(|t| t.differs(split)) {
                return Err(refuse(format!("{} trained on another split than this run's: {why}", checkpoint.display())));
            }
            if meta.provenance.val_fold != Some(val_fold) || meta.normalization != *normalization {
                return Err(refuse(format!(
                    "{} was trained on another split than this run's (validation fold {:?}, normalisation fitted on other touches)",
                    checkpoint.display(),
                    meta.provenance.val_fold
                )));
            }
            if meta.classes != classes {
                return Err(refuse(format!("{} answers other classes than this run's", checkpoint.display())));
            }
            models.push(model);
        }
        if models.is_empty() {
            return Err(refuse(format!("no trained run of validation fold {val_fold} (seed*/fold{val_fold}/model) to learn from")));
        }
        Ok(Self { models })
    }

    /// The teachers' mean class probabilities for the windows `x`, outside the gradient.
    pub fn probabilities(&self, x: &Tensor) -> Result<Tensor> {
        let mut sum: Option<Tensor> = None;
        for model in &self.models {
            let p = candle_nn::ops::softmax_last_dim(&model.forward(x, None)?.detach())?;
            sum = Some(match sum {
                Some(s) => (s + p)?,
                None => p,
            });
        }
        Ok((sum.expect("at least one teacher, as load ensures") / self.models.len() as f64)?)
    }
}

/// The cross-entropy of `logits` against the probabilities `target`, averaged over the batch.
pub fn soft_cross_entropy(logits: &Tensor, target: &Tensor) -> Result<Tensor> {
    let log_q = candle_nn::ops::log_softmax(logits, D::Minus1)?;
    Ok((target * log_q)?.sum(D::Minus1)?.mean_all()?.neg()?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::Device;

    #[test]
    fn soft_cross_entropy_of_a_one_hot_target_is_the_cross_entropy() {
        let logits = Tensor::new(&[[1.0f32, 2.0, 0.5], [0.0, -1.0, 3.0]], &Device::Cpu).unwrap();
        let one_hot = Tensor::new(&[[0.0f32, 1.0, 0.0], [1.0, 0.0, 0.0]], &Device::Cpu).unwrap();
        let labels = Tensor::new(&[1u32, 0], &Device::Cpu).unwrap();
        let soft = soft_cross_entropy(&logits, &one_hot).unwrap().to_scalar::<f32>().unwrap();
        let hard = candle_nn::loss::cross_entropy(&logits, &labels).unwrap().to_scalar::<f32>().unwrap();
        assert!((soft - hard).abs() < 1e-6, "{soft} against {hard}");
        // A uniform target over 3 classes: the mean of -log q over the classes.
        let uniform = Tensor::full(1.0f32 / 3.0, (2, 3), &Device::Cpu).unwrap();
        let got = soft_cross_entropy(&logits, &uniform).unwrap().to_scalar::<f32>().unwrap();
        let log_q = candle_nn::ops::log_softmax(&logits, D::Minus1).unwrap().to_vec2::<f32>().unwrap();
        let want = -log_q.iter().flatten().sum::<f32>() / 6.0;
        assert!((got - want).abs() < 1e-6, "{got} against {want}");
    }
}
