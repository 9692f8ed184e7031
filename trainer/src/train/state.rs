//! A run's state between epochs, as `last/state.json` keeps it: epochs and steps done, the random
//! draws' state, each sensor's best epoch so far and the wall time; and what it decides: whether
//! `--patience` has ended the run.

use pvt3_models::Rng;
use serde::{Deserialize, Serialize};

use super::sensor::Best;
use crate::options::TrainOptions;

/// What `last/state.json` remembers between epochs.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct RunState {
    pub(super) epochs_done: usize,
    pub(super) step: usize,
    pub(super) rng: Rng,
    pub(super) best: Option<Best>,
    /// A joint run's: the partner network's best epoch so far.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) partner_best: Option<Best>,
    pub(super) wall_seconds: f64,
}

impl RunState {
    /// A run's state before its first epoch: its draws seeded from the options' seed.
    pub(super) fn fresh(opts: &TrainOptions) -> Self {
        let rng = Rng::new(opts.seed.wrapping_add(1));
        Self { epochs_done: 0, step: 0, rng, best: None, partner_best: None, wall_seconds: 0.0 }
    }

    /// The best epoch so far of the run's sensor `i` (0: the run's own, 1: a joint run's other).
    pub(super) fn best_of(&mut self, i: usize) -> &mut Option<Best> {
        if i == 0 {
            &mut self.best
        } else {
            &mut self.partner_best
        }
    }

    /// Whether `--patience` stops the run after its epochs done: every sensor's validation has
    /// not improved for that many epochs. Asked before an epoch, not after, so that a run
    /// interrupted after its last epoch stops where it would have.
    pub(super) fn stalled(&mut self, sensors: usize, patience: Option<usize>) -> bool {
        let Some(patience) = patience.filter(|p| *p > 0) else { return false };
        let done = self.epochs_done;
        (0..sensors).all(|i| self.best_of(i).as_ref().is_some_and(|b| done >= b.epoch + patience))
    }
}
