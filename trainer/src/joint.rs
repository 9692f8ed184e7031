//! Joint learning across two sensors, as Gao et al. trained their iCub and BioTac networks
//! (dexrob/Supervised-Autoencoder-Joint-Learning-on-Heterogeneous-Tactile-Sensory-Data,
//! `code/T1_BT19_Icub_joint_ae.py`): a network per sensor, trained together on batches whose
//! touches pair up by class, each on its own classification loss, plus the mean squared error
//! between the two networks' encodings of each pair once the first epochs are done. Each network
//! keeps its own head and is validated, selected and tested on its own sensor alone; each is
//! pruned, baked and exported alone.
//!
//! Pairs are drawn within each sensor's own training split, so no test or validation touch of
//! either sensor is ever trained on. The two data sets must name the same classes in the same
//! order; their touches need not be in any order.

use pvt3_models::{Config, Rng};

use crate::data::Dataset;
use crate::options::TrainOptions;
use crate::{Error, Result};

/// The second sensor of a joint run: its data, its network's configuration and class names. Its
/// run is a run directory of its own inside the run's (`run_dir::Run::partner`).
#[derive(Clone)]
pub struct Partner<'a> {
    pub data: &'a Dataset,
    pub config: Config,
    pub classes: Vec<String>,
}

impl Partner<'_> {
    /// Refuses what joint learning cannot pair or compare: networks other than PVT³, encodings
    /// of different widths, other classes, and mixup (a blend of two touches has no partner);
    /// and a partner that would train on the run's test touches: the same touches as `data`, or
    /// a set that records the condition `data` holds levels of out without holding them out too.
    pub fn check(&self, data: &Dataset, config: &Config, classes: &[String], opts: &TrainOptions) -> Result<()> {
        let refuse = |reason: String| Err(Error::Usage(format!("--joint {}: {reason}", self.data.path.display())));
        if opts.joint.is_none() {
            return refuse("a partner sensor without joint-learning options".into());
        }
        if self.data.digest() == data.digest() {
            return refuse(format!("it holds the same touches as {}: a sensor cannot train beside itself", data.path.display()));
        }
        if let Some(h) = &data.held_out {
            let holds = |p: &crate::data::HoldOut| p.same_touches(h);
            if self.data.conditions.iter().any(|c| c.name == h.condition) && !self.data.held_out.as_ref().is_some_and(holds) {
                return refuse(format!(
                    "it records {} too and does not hold out {h}: those touches would train the network beside",
                    h.condition
                ));
            }
        }
        config.require_pvt3("--joint")?;
        self.config.require_pvt3("--joint (the other sensor's network)")?;
        if config.dim != self.config.dim {
            return refuse(format!(
                "its network encodes touches in {} values and this one in {}; the two encodings are compared (--set dim=N sets both)",
                self.config.dim, config.dim
            ));
        }
        if classes != self.classes.as_slice() {
            return refuse(format!("it names the classes {:?}, and this data set {:?}; pairs are made by class", self.classes, classes));
        }
        if opts.augmentation.mixup > 0.0 {
            return refuse("--mixup blends touches of two classes, which have no partner; train with one or the other".into());
        }
        if opts.distillation.teachers.is_some() {
            return refuse("--distill teaches one sensor's network by its own runs; train with one or the other".into());
        }
        Ok(())
    }

    /// The partner's own options: the run's, recording this run's data set as its partner.
    pub fn options(opts: &TrainOptions, data: &Dataset) -> TrainOptions {
        let mut options = opts.clone();
        if let Some(joint) = &mut options.joint {
            joint.partner = data.path.display().to_string();
        }
        options
    }
}

/// For each label, a row of the partner's training windows of that class (`same_class[label]`),
/// drawn by `rng`.
pub fn draw_partners(labels: impl Iterator<Item = u32>, same_class: &[Vec<usize>], rng: &mut Rng) -> Result<Vec<usize>> {
    labels
        .map(|label| match same_class.get(label as usize) {
            Some(rows) if !rows.is_empty() => Ok(rows[rng.below(rows.len())]),
            _ => Err(Error::Usage(format!("--joint: the other sensor has no training touch of class {label} to pair with"))),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_partner_is_drawn_from_the_same_class_only() {
        let same_class = vec![vec![0, 3], vec![1], vec![2, 4, 5]];
        let mut rng = Rng::new(7);
        let labels = [2u32, 0, 1, 2, 2, 0, 1];
        for _ in 0..20 {
            let rows = draw_partners(labels.iter().copied(), &same_class, &mut rng).unwrap();
            assert_eq!(rows.len(), labels.len());
            for (row, label) in rows.iter().zip(labels) {
                assert!(same_class[label as usize].contains(row), "row {row} for class {label}");
            }
        }
        // Every row of a class is drawn, in time.
        let drawn: std::collections::BTreeSet<usize> =
            (0..50).flat_map(|_| draw_partners([2u32].into_iter(), &same_class, &mut rng).unwrap()).collect();
        assert_eq!(drawn, [2, 4, 5].into());
        let err = draw_partners([1u32, 3].into_iter(), &same_class, &mut rng).unwrap_err().to_string();
        assert!(err.contains("no training touch of class 3"), "{err}");
    }
}
