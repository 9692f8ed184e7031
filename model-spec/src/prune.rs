//! Pruning plans: which entries of the selection masks to set to zero.
//!
//! Channel pruning removes the `p` % of channel-mask entries with the smallest |score|: per mask
//! (local; for attention, per head, so heads stay equal in width) or below one threshold over all
//! channel masks (global). Frame pruning removes the `q` % of temporal tokens with the smallest
//! |frame-mask| value, patch pruning the `r` % of the grid's patches with the smallest
//! |patch-mask| value (a model with `patch_selection`), or the patches the parent run's validation
//! fold misses least ([`PatchChoice::Validation`], chosen by the trainer, which holds the data).
//! Entries already zero count as the smallest.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::names::{self, Role};
use crate::weights::Tensors;
use crate::{Config, Error, Result};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Scope {
    /// The same share of every mask (of every head, for attention).
    #[default]
    Local,
    /// One threshold over all channel masks.
    Global,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PruneSpec {
    /// Percentage of channel-mask entries to remove.
    pub channels: f64,
    /// Percentage of temporal tokens to remove.
    pub frames: f64,
    /// Percentage of the grid's patches to remove (a model with a patch mask); written only when
    /// not zero, so that earlier runs' records read and write as before.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub patches: f64,
    pub scope: Scope,
    /// How the patches to prune are chosen; written only when not by magnitude, so that earlier
    /// runs' records read and write as before.
    #[serde(default, skip_serializing_if = "PatchChoice::is_magnitude")]
    pub patch_choice: PatchChoice,
    /// Percentage of the entries of every weight matrix set to zero at random and kept there
    /// (persistent random unstructured pruning, [`random_weights`]). It regularises; it makes the
    /// model no smaller, since the matrices stay dense.
    #[serde(default)]
    pub weights: f64,
}

/// How patch pruning chooses the patches it removes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum PatchChoice {
    /// The patches with the smallest |patch-mask| value.
    #[default]
    Magnitude,
    /// One patch at a time, the one without which the parent run's validation fold has the lowest
    /// loss (greedy backward elimination).
    Validation,
}

impl PatchChoice {
    fn is_magnitude(&self) -> bool {
        *self == Self::Magnitude
    }
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

/// Zeroes `percent` % of the entries of every weight matrix in `tensors` ([`Role::Matrix`]),
/// chosen at random by `seed`: the exact count in each matrix, as PyTorch's `random_unstructured`
/// does.
pub fn random_weights(tensors: &mut Tensors, percent: f64, seed: u64) -> Result<()> {
    check_percent("weights", percent)?;
    let mut rng = crate::Rng::new(seed);
    for (name, (shape, values)) in tensors.iter_mut() {
        if Role::of(name, shape.len()) != Role::Matrix {
            continue;
        }
        let mut order: Vec<usize> = (0..values.len()).collect();
        rng.shuffle(&mut order);
        for &i in order.iter().take(share(values.len(), percent)) {
            values[i] = 0.0;
        }
    }
    Ok(())
}

/// `percent` as a share of `what` to prune: from 0 to 100.
fn check_percent(what: &str, percent: f64) -> Result<()> {
    if !(0.0..=100.0).contains(&percent) {
        return Err(Error::Config(format!("cannot prune {percent} % of the {what}: give a percentage from 0 to 100")));
    }
    Ok(())
}

/// For each mask name, which entries are kept.
pub type Plan = BTreeMap<String, Vec<bool>>;

/// The channel masks of a configuration: (name, groups), a group being one head or one FFN.
fn channel_masks(cfg: &Config) -> Vec<(String, usize)> {
    let mut masks = Vec::new();
    for (stage, depth) in names::stages(cfg) {
        for i in 0..depth {
            let layer = names::layer(stage, i);
            masks.push((names::join(&[&layer, names::ATTN, names::CHANNEL_MASK]), cfg.heads));
            masks.push((names::join(&[&layer, names::FFN, names::CHANNEL_MASK]), 1));
        }
    }
    masks
}

/// Keeps all but the `remove` entries of `scores` with the smallest magnitude.
fn keep_largest(scores: &[f32], remove: usize) -> Vec<bool> {
    let mut order: Vec<usize> = (0..scores.len()).collect();
    order.sort_by(|&a, &b| scores[a].abs().total_cmp(&scores[b].abs()).then(a.cmp(&b)));
    let mut keep = vec![true; scores.len()];
    order.into_iter().take(remove).for_each(|i| keep[i] = false);
    keep
}

fn share(n: usize, percent: f64) -> usize {
    ((n as f64 * percent / 100.0).round() as usize).min(n)
}

/// The plan for `spec` over the masks in `tensors`.
pub fn plan(cfg: &Config, tensors: &Tensors, spec: &PruneSpec) -> Result<Plan> {
    cfg.require_pvt3("pruning")?;
    for (what, p) in [("channels", spec.channels), ("frames", spec.frames), ("patches", spec.patches)] {
        check_percent(what, p)?;
    }
    if spec.patches > 0.0 && !cfg.patch_selection() {
        return Err(Error::Config(format!(
            "cannot prune {} % of the patches of a model without a patch mask: train it with --set patch_selection=true",
            spec.patches
        )));
    }
    let get = |name: &str| -> Result<&Vec<f32>> {
        tensors.get(name).map(|(_, v)| v).ok_or_else(|| Error::MissingTensor { task: "prune", name: name.into() })
    };
    let mut plan = Plan::new();
    let masks = channel_masks(cfg);
    match spec.scope {
        Scope::Local => {
            for (name, groups) in &masks {
                let scores = get(name)?;
                let width = scores.len() / groups;
                let keep = scores.chunks(width).flat_map(|g| keep_largest(g, share(width, spec.channels))).collect();
                plan.insert(name.clone(), keep);
            }
        }
        Scope::Global => {
            let all: Vec<(usize, usize, f32)> = masks
                .iter()
                .enumerate()
                .map(|(m, (name, _))| get(name).map(|s| s.iter().enumerate().map(move |(i, v)| (m, i, *v))))
                .collect::<Result<Vec<_>>>()?
                .into_iter()
                .flatten()
                .collect();
            let keep = keep_largest(&all.iter().map(|e| e.2).collect::<Vec<_>>(), share(all.len(), spec.channels));
            for (m, (name, _)) in masks.iter().enumerate() {
                let flags = all.iter().zip(&keep).filter(|(e, _)| e.0 == m).map(|(_, k)| *k).collect();
                plan.insert(name.clone(), flags);
            }
        }
    }
    let frames = get(names::FRAME_MASK)?;
    plan.insert(names::FRAME_MASK.into(), keep_largest(frames, share(frames.len(), spec.frames)));
    if cfg.patch_selection() {
        let patches = get(names::PATCH_MASK)?;
        plan.insert(names::PATCH_MASK.into(), keep_largest(patches, share(patches.len(), spec.patches)));
    }
    Ok(plan)
}

/// Sets the entries the plan removes to zero.
pub fn apply(plan: &Plan, tensors: &mut Tensors) {
    for (name, keep) in plan {
        if let Some((_, values)) = tensors.get_mut(name) {
            values.iter_mut().zip(keep).filter(|(_, k)| !**k).for_each(|(v, _)| *v = 0.0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tensors(cfg: &Config, score: impl Fn(&str, usize) -> f32) -> Tensors {
        let mut t = Tensors::new();
        for (name, _) in channel_masks(cfg) {
            let n = if name.contains("attn") { cfg.inner_dim() } else { cfg.mlp_dim };
            t.insert(name.clone(), (vec![n], (0..n).map(|i| score(&name, i)).collect()));
        }
        let n = cfg.time_tokens();
        t.insert("frame_mask".into(), (vec![n], (0..n).map(|i| score("frame_mask", i)).collect()));
        t
    }

    #[test]
    fn local_pruning_takes_the_same_share_of_every_head_by_magnitude() {
        let cfg = Config { heads: 2, dim_head: 4, mlp_dim: 8, ..Config::icub20() };
        // Scores alternate in sign; magnitudes rise with the index inside each head.
        let t = tensors(&cfg, |_, i| if i % 2 == 0 { (i % 4) as f32 } else { -((i % 4) as f32) });
        let p = plan(
            &cfg,
            &t,
            &PruneSpec {
                channels: 50.0,
                frames: 40.0,
                patches: 0.0,
                scope: Scope::Local,
                weights: 0.0,
                patch_choice: PatchChoice::Magnitude,
            },
        )
        .unwrap();
        assert_eq!(p["space.layers.0.attn.channel_mask"], vec![false, false, true, true, false, false, true, true]);
        assert_eq!(p["space.layers.0.ffn.channel_mask"].iter().filter(|k| !**k).count(), 4);
        assert_eq!(p["frame_mask"].iter().filter(|k| !**k).count(), 30);
    }

    #[test]
    fn global_pruning_uses_one_threshold() {
        let cfg = Config::icub20();
        // Temporal masks score high, spatial ones low: global pruning takes the spatial ones first.
        let t = tensors(&cfg, |name, i| if name.starts_with("space") { 0.1 + i as f32 * 1e-3 } else { 1.0 });
        let p = plan(
            &cfg,
            &t,
            &PruneSpec {
                channels: 50.0,
                frames: 0.0,
                patches: 0.0,
                scope: Scope::Global,
                weights: 0.0,
                patch_choice: PatchChoice::Magnitude,
            },
        )
        .unwrap();
        assert!(p["space.layers.2.attn.channel_mask"].iter().all(|k| !k));
        assert!(p["temporal.layers.2.ffn.channel_mask"].iter().all(|k| *k));
        assert!(p["frame_mask"].iter().all(|k| *k));
        let mut pruned = t.clone();
        apply(&p, &mut pruned);
        assert!(pruned["space.layers.0.ffn.channel_mask"].1.iter().all(|v| *v == 0.0));
        let err = plan(
            &cfg,
            &t,
            &PruneSpec {
                channels: 120.0,
                frames: 0.0,
                patches: 0.0,
                scope: Scope::Local,
                weights: 0.0,
                patch_choice: PatchChoice::Magnitude,
            },
        )
        .unwrap_err();
        assert!(err.to_string().contains("give a percentage from 0 to 100"));
    }

    #[test]
    fn patch_pruning_takes_the_smallest_patch_mask_values_of_a_model_with_one() {
        let cfg = Config { network: crate::Pvt3Config { patch_selection: true, ..Default::default() }.into(), ..Config::icub20() };
        let mut t = tensors(&cfg, |_, _| 1.0);
        t.insert(names::PATCH_MASK.into(), (vec![4], vec![0.9, -0.2, 0.5, 1.1]));
        let spec = PruneSpec {
            channels: 0.0,
            frames: 0.0,
            patches: 50.0,
            scope: Scope::Local,
            weights: 0.0,
            patch_choice: PatchChoice::Magnitude,
        };
        assert_eq!(plan(&cfg, &t, &spec).unwrap()[names::PATCH_MASK], vec![true, false, false, true]);
        let err = plan(&Config::icub20(), &t, &spec).unwrap_err().to_string();
        assert!(err.contains("without a patch mask: train it with --set patch_selection=true"), "{err}");
    }
}
